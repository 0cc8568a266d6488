//! The telemetry frame's wire layout: every multi-byte field at a fixed width, little-endian.
//!
//! As postcard varints the telemetry payload took 59-87 bytes: a u32 or i32 up to 5 bytes, a
//! u16 or i16 up to 3, so the frame's true worst case was 97 bytes on the wire although the
//! values a robot sends kept it near 76. Varints pay off for small numbers; most telemetry
//! numbers are not small (the clock, wrapping encoder counts, the cycle period in µs,
//! millivolts, a pose in mm), so here each field takes exactly its type's width. The payload is
//! always 70 bytes and the frame always 80 (PROTOCOL.md §2, §6), whatever the values, with
//! every type and range unchanged: nothing is narrowed, clamped or rescaled.
//!
//! Layer: serde glue, no_std. `Telemetry` (in `msg`) is what the firmware and the station use;
//! it serialises through [`TelemetryWire`] (`#[serde(from, into)]`), whose schema is the
//! `Telemetry` entry of the fingerprint. Every byte pattern of a fixed field decodes, so only
//! `mode` (an enum index) can make a telemetry payload invalid.

use postcard_schema::{schema::NamedType, Schema};
use serde::de::{Error as _, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::msg::{Beacon, BehaviourOut, CycleTiming, Mode, Pose, PoseSigma, Telemetry, Wheels};
use crate::packed::Packed10x8;

/// Reads `N` bytes written as a serde tuple (postcard: the bytes, no length).
fn bytes<'de, D: Deserializer<'de>, const N: usize>(d: D) -> Result<[u8; N], D::Error> {
    struct V<const N: usize>;
    impl<'de, const N: usize> Visitor<'de> for V<N> {
        type Value = [u8; N];
        fn expecting(&self, f: &mut core::fmt::Formatter) -> core::fmt::Result {
            write!(f, "{N} bytes of a fixed-width integer")
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
            let mut out = [0u8; N];
            for (i, b) in out.iter_mut().enumerate() {
                *b = seq
                    .next_element()?
                    .ok_or_else(|| A::Error::invalid_length(i, &self))?;
            }
            Ok(out)
        }
    }
    d.deserialize_tuple(N, V::<N>)
}

macro_rules! fixed_int {
    ($(#[$doc:meta])* $name:ident, $int:ty, $n:literal, $schema:literal) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
        pub struct $name(pub $int);

        impl Serialize for $name {
            fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                self.0.to_le_bytes().serialize(s)
            }
        }

        impl<'de> Deserialize<'de> for $name {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                Ok($name(<$int>::from_le_bytes(bytes::<D, $n>(d)?)))
            }
        }

        impl Schema for $name {
            const SCHEMA: &'static NamedType = &NamedType {
                name: $schema,
                ty: <[u8; $n] as Schema>::SCHEMA.ty,
            };
        }
    };
}

fixed_int!(
    /// A `u32` in 4 bytes, little-endian.
    LeU32, u32, 4, "le_u32"
);
fixed_int!(
    /// An `i32` in 4 bytes, little-endian (two's complement).
    LeI32, i32, 4, "le_i32"
);
fixed_int!(
    /// A `u16` in 2 bytes, little-endian.
    LeU16, u16, 2, "le_u16"
);
fixed_int!(
    /// An `i16` in 2 bytes, little-endian (two's complement).
    LeI16, i16, 2, "le_i16"
);

/// Bytes of a telemetry payload: every one of them, always.
pub const TELEMETRY_PAYLOAD: usize = 70;

/// `Telemetry` as it travels: the same fields in the same order (PROTOCOL.md §6), flattened,
/// each multi-byte one at its type's fixed width. The schema is named `Telemetry`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
#[allow(missing_docs)]
pub struct TelemetryWire {
    pub time_ms: LeU32,
    /// One byte: an enum index below 128.
    pub mode: Mode,
    pub x_mm: LeI32,
    pub y_mm: LeI32,
    pub heading_mrad: LeI16,
    pub sigma_xy_mm: LeU16,
    pub sigma_heading_mrad: LeU16,
    pub speed_mm_s: [LeI16; 2],
    pub encoders: [LeU16; 2],
    pub ir: Packed10x8,
    pub light: Packed10x8,
    pub compass_ddeg: LeU16,
    pub flags: u8,
    pub line_events: u8,
    pub beacon_bearing_ddeg: LeI16,
    pub beacon_strength: u8,
    pub battery_mv: LeU16,
    pub behaviour_active: u8,
    pub motor_mm_s: [LeI16; 2],
    pub cycle_period_us: LeU32,
    pub cycle_busy_us: LeU32,
    pub cycle_overruns: u8,
}

impl From<Telemetry> for TelemetryWire {
    fn from(t: Telemetry) -> Self {
        TelemetryWire {
            time_ms: LeU32(t.time_ms),
            mode: t.mode,
            x_mm: LeI32(t.pose.x_mm),
            y_mm: LeI32(t.pose.y_mm),
            heading_mrad: LeI16(t.pose.heading_mrad),
            sigma_xy_mm: LeU16(t.sigma.xy_mm),
            sigma_heading_mrad: LeU16(t.sigma.heading_mrad),
            speed_mm_s: t.wheels.speed_mm_s.map(LeI16),
            encoders: t.wheels.encoders.map(LeU16),
            ir: t.ir,
            light: t.light,
            compass_ddeg: LeU16(t.compass_ddeg),
            flags: t.flags,
            line_events: t.line_events,
            beacon_bearing_ddeg: LeI16(t.beacon.bearing_ddeg),
            beacon_strength: t.beacon.strength,
            battery_mv: LeU16(t.battery_mv),
            behaviour_active: t.behaviour.active,
            motor_mm_s: t.behaviour.motor_mm_s.map(LeI16),
            cycle_period_us: LeU32(t.cycle.period_us),
            cycle_busy_us: LeU32(t.cycle.busy_us),
            cycle_overruns: t.cycle.overruns,
        }
    }
}

impl From<TelemetryWire> for Telemetry {
    fn from(w: TelemetryWire) -> Self {
        Telemetry {
            time_ms: w.time_ms.0,
            mode: w.mode,
            pose: Pose {
                x_mm: w.x_mm.0,
                y_mm: w.y_mm.0,
                heading_mrad: w.heading_mrad.0,
            },
            sigma: PoseSigma {
                xy_mm: w.sigma_xy_mm.0,
                heading_mrad: w.sigma_heading_mrad.0,
            },
            wheels: Wheels {
                speed_mm_s: w.speed_mm_s.map(|v| v.0),
                encoders: w.encoders.map(|v| v.0),
            },
            ir: w.ir,
            light: w.light,
            compass_ddeg: w.compass_ddeg.0,
            flags: w.flags,
            line_events: w.line_events,
            beacon: Beacon {
                bearing_ddeg: w.beacon_bearing_ddeg.0,
                strength: w.beacon_strength,
            },
            battery_mv: w.battery_mv.0,
            behaviour: BehaviourOut {
                active: w.behaviour_active,
                motor_mm_s: w.motor_mm_s.map(|v| v.0),
            },
            cycle: CycleTiming {
                period_us: w.cycle_period_us.0,
                busy_us: w.cycle_busy_us.0,
                overruns: w.cycle_overruns,
            },
        }
    }
}

impl Schema for Telemetry {
    const SCHEMA: &'static NamedType = &NamedType {
        name: "Telemetry",
        ty: TelemetryWire::SCHEMA.ty,
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_integers_are_little_endian_at_their_width() {
        let mut buf = [0u8; 16];
        let n = postcard::to_slice(&(LeU32(0x0102_0304), LeI16(-2)), &mut buf)
            .map(|b| b.len())
            .unwrap_or(0);
        assert_eq!(&buf[..n], &[4, 3, 2, 1, 0xfe, 0xff]);
        let back: (LeU32, LeI16) = postcard::from_bytes(&buf[..n]).unwrap_or_default();
        assert_eq!(back, (LeU32(0x0102_0304), LeI16(-2)));
    }

    #[test]
    fn every_telemetry_payload_is_the_same_length() {
        let mut buf = [0u8; 128];
        for t in [Telemetry::default(), widest()] {
            let n = postcard::to_slice(&t, &mut buf)
                .map(|b| b.len())
                .unwrap_or(0);
            assert_eq!(n, TELEMETRY_PAYLOAD);
            assert_eq!(postcard::from_bytes::<Telemetry>(&buf[..n]).ok(), Some(t));
        }
    }

    fn widest() -> Telemetry {
        Telemetry {
            time_ms: u32::MAX,
            mode: Mode::CalibrateLight,
            pose: Pose {
                x_mm: i32::MIN,
                y_mm: i32::MAX,
                heading_mrad: i16::MIN,
            },
            sigma: PoseSigma {
                xy_mm: u16::MAX,
                heading_mrad: u16::MAX,
            },
            wheels: Wheels {
                speed_mm_s: [i16::MIN, i16::MAX],
                encoders: [u16::MAX; 2],
            },
            ir: Packed10x8::new([1023; 8]),
            light: Packed10x8::new([1023; 8]),
            compass_ddeg: u16::MAX,
            flags: u8::MAX,
            line_events: u8::MAX,
            beacon: Beacon {
                bearing_ddeg: i16::MIN,
                strength: u8::MAX,
            },
            battery_mv: u16::MAX,
            behaviour: BehaviourOut {
                active: u8::MAX,
                motor_mm_s: [i16::MIN; 2],
            },
            cycle: CycleTiming {
                period_us: u32::MAX,
                busy_us: u32::MAX,
                overruns: u8::MAX,
            },
        }
    }
}
