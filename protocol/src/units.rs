//! Lengths on the wire: whole millimetres in an `i32` (positions, map origins, PROTOCOL.md §6
//! and §12), about ±2147 km. Every metres-to-millimetres conversion goes through here, so a
//! value that does not fit is refused with the field's name instead of being clamped by `as`
//! (which turns 5,000 km into 2147483647 mm and NaN into 0).
//!
//! Layer: pure, no_std, no float library: rounding is done by hand (halves away from zero,
//! as `f64::round`), exactly for every value in range.

use core::fmt;

use crate::PointMm;

/// Largest length the wire carries, metres.
pub const MAX_M: f64 = i32::MAX as f64 / 1000.0;
/// Smallest length the wire carries, metres.
pub const MIN_M: f64 = i32::MIN as f64 / 1000.0;

/// A length that does not fit the wire's whole millimetres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutOfRange {
    /// What the value is ("origin x", "--goal y", ...).
    pub field: &'static str,
    pub metres: f64,
}

impl fmt::Display for OutOfRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} {} m does not fit the link's whole millimetres ({MIN_M} .. {MAX_M} m)",
            self.field, self.metres
        )
    }
}

impl core::error::Error for OutOfRange {}

/// `metres` in whole millimetres, rounded to nearest; `field` names it in the error.
pub fn mm_from_m(field: &'static str, metres: f64) -> Result<i32, OutOfRange> {
    let v = metres * 1000.0;
    // Checked before converting: NaN, infinities and anything rounding outside i32 fail.
    if !(v > f64::from(i32::MIN) - 0.5 && v < f64::from(i32::MAX) + 0.5) {
        return Err(OutOfRange { field, metres });
    }
    // `as` truncates toward zero; in this range it and the fraction left are exact.
    let whole = v as i64;
    let frac = v - whole as f64;
    let rounded = if frac >= 0.5 {
        whole + 1
    } else if frac <= -0.5 {
        whole - 1
    } else {
        whole
    };
    i32::try_from(rounded).map_err(|_| OutOfRange { field, metres })
}

/// A map-frame point in metres as the wire's `PointMm`; `fields` name x and y in the error.
pub fn point_mm(fields: [&'static str; 2], (x, y): (f64, f64)) -> Result<PointMm, OutOfRange> {
    Ok(PointMm {
        x_mm: mm_from_m(fields[0], x)?,
        y_mm: mm_from_m(fields[1], y)?,
    })
}

/// The same, clamped to the range (NaN to 0): only for a simulation's own poses, whose world
/// was checked to fit when it was loaded, so a clamp means the robot left the arena.
pub fn mm_from_m_clamped(metres: f64) -> i32 {
    match mm_from_m("", metres) {
        Ok(mm) => mm,
        Err(_) if metres > 0.0 => i32::MAX,
        Err(_) if metres < 0.0 => i32::MIN,
        Err(_) => 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounds_like_f64_round_across_the_range() {
        for m in [
            0.0,
            0.0004,
            0.0005,
            -0.0005,
            1.2345,
            -1.2345,
            0.3,
            2.5e-4,
            1e-9,
            2147483.647,
            -2147483.648,
            2147483.6474,
            -2147483.6484,
            123456.7895,
        ] {
            assert_eq!(mm_from_m("x", m), Ok((m * 1000.0).round() as i32), "{m}");
        }
    }

    #[test]
    fn values_beyond_i32_millimetres_are_refused_by_name() {
        for m in [
            2147483.6475,
            -2147483.6485,
            5_000_000.0,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ] {
            let e = mm_from_m("origin x", m).unwrap_err();
            assert_eq!(e.field, "origin x");
        }
        extern crate std;
        use std::string::ToString;
        let e = mm_from_m("origin x", 5_000_000.0).unwrap_err();
        assert_eq!(
            e.to_string(),
            "origin x 5000000 m does not fit the link's whole millimetres \
             (-2147483.648 .. 2147483.647 m)"
        );
        assert_eq!(mm_from_m_clamped(5_000_000.0), i32::MAX);
        assert_eq!(mm_from_m_clamped(f64::NAN), 0);
    }
}
