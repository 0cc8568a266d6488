//! Netpbm greyscale images: binary P5 and plain (ASCII) P2, 8- or 16-bit, for ROS maps.
//!
//! Layer: a decoder under [`super::rosmap`]; bytes in, pixels out, no I/O.
//! Invariant of a decoded [`Pgm`]: `pixels.len() == width * height`, every pixel <= `maxval`,
//! rows top to bottom as in the file.
//! What can fail: a wrong magic (PNG, PBM, PPM are named as such), header numbers missing,
//! zero, or past [`MAX_GRID_SIDE`], maxval outside 1..=65535, truncated pixel data, a pixel above
//! maxval. P5 errors give the byte offset; P2 errors give line:column.

use std::path::Path;

use super::error::{to_u32, ArenaError, Position};
use super::MAX_GRID_SIDE;

/// A decoded greyscale image.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Pgm {
    pub width: u32,
    pub height: u32,
    pub maxval: u16,
    /// Row-major, top row first.
    pub pixels: Vec<u16>,
    /// Offset of non-whitespace data after the image, if any (map_server ignores it).
    pub trailing: Option<usize>,
}

struct Reader<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    at: usize,
    plain: bool,
}

impl Reader<'_> {
    fn position(&self, offset: usize) -> Position {
        if self.plain {
            let before = &self.bytes[..offset.min(self.bytes.len())];
            let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
            let start = before
                .iter()
                .rposition(|&b| b == b'\n')
                .map_or(0, |i| i + 1);
            Position::Line {
                line: to_u32(line),
                column: Some(to_u32(offset - start + 1)),
            }
        } else {
            Position::Byte(offset as u64)
        }
    }

    fn err(&self, offset: usize, msg: impl Into<String>) -> ArenaError {
        ArenaError::at(self.path, self.position(offset), msg)
    }

    /// Skips whitespace and `#` comments (to end of line).
    fn skip_space(&mut self) {
        while let Some(&b) = self.bytes.get(self.at) {
            if b == b'#' {
                while self.bytes.get(self.at).is_some_and(|&b| b != b'\n') {
                    self.at += 1;
                }
            } else if b.is_ascii_whitespace() {
                self.at += 1;
            } else {
                break;
            }
        }
    }

    /// The next decimal number, with the offset it starts at.
    fn number(&mut self, what: &str) -> Result<(u64, usize), ArenaError> {
        self.skip_space();
        let start = self.at;
        let mut v: u64 = 0;
        while let Some(&b) = self.bytes.get(self.at).filter(|b| b.is_ascii_digit()) {
            v = v.saturating_mul(10).saturating_add(u64::from(b - b'0'));
            self.at += 1;
        }
        if self.at == start {
            return Err(match self.bytes.get(start) {
                None => self.err(start, format!("truncated: the file ends before the {what}")),
                Some(&b) => self.err(
                    start,
                    format!(
                        "expected the {what} (a decimal number), found {:?}",
                        char::from(b)
                    ),
                ),
            });
        }
        // A number glued to junk ("12x") is not a number either.
        if let Some(&b) = self
            .bytes
            .get(self.at)
            .filter(|b| !b.is_ascii_whitespace() && **b != b'#')
        {
            return Err(self.err(
                self.at,
                format!("unexpected {:?} after the {what}", char::from(b)),
            ));
        }
        Ok((v, start))
    }
}

/// Decodes a P5 or P2 PGM.
pub(crate) fn decode(path: &Path, bytes: &[u8]) -> Result<Pgm, ArenaError> {
    let magic = bytes.get(..2).unwrap_or(bytes);
    let plain = match magic {
        b"P5" => false,
        b"P2" => true,
        _ => {
            let what = if bytes.starts_with(b"\x89PNG") {
                "a PNG image; convert it to PGM (e.g. `convert map.png map.pgm`)".to_string()
            } else if matches!(magic, b"P1" | b"P4") {
                "a PBM (bitmap) image; a map needs a greyscale PGM (P5 or P2)".to_string()
            } else if matches!(magic, b"P3" | b"P6") {
                "a PPM (colour) image; convert it to a greyscale PGM (P5 or P2)".to_string()
            } else {
                "not a PGM image: it does not start with P5 or P2".to_string()
            };
            return Err(ArenaError::at(path, Position::Byte(0), what));
        }
    };
    let mut r = Reader {
        path,
        bytes,
        at: 2,
        plain,
    };
    let (w, w_at) = r.number("width")?;
    let (h, h_at) = r.number("height")?;
    let (maxval, m_at) = r.number("maxval")?;
    for (v, at, what) in [(w, w_at, "width"), (h, h_at, "height")] {
        if v == 0 || v > u64::from(MAX_GRID_SIDE) {
            return Err(r.err(at, format!("image {what} {v} must be 1..={MAX_GRID_SIDE}")));
        }
    }
    if maxval == 0 || maxval > 65535 {
        return Err(r.err(m_at, format!("maxval {maxval} must be 1..=65535")));
    }
    let maxval = u16::try_from(maxval).unwrap_or(u16::MAX);
    let (width, height) = (to_u32(w as usize), to_u32(h as usize));
    let count = (w * h) as usize;
    let (pixels, trailing) = if plain {
        plain_pixels(&mut r, count, maxval)?
    } else {
        binary_pixels(&r, count, maxval)?
    };
    Ok(Pgm {
        width,
        height,
        maxval,
        pixels,
        trailing,
    })
}

fn binary_pixels(
    r: &Reader<'_>,
    count: usize,
    maxval: u16,
) -> Result<(Vec<u16>, Option<usize>), ArenaError> {
    // Exactly one whitespace byte separates maxval from the data (the data may begin with
    // bytes that look like whitespace, so no more are skipped).
    match r.bytes.get(r.at) {
        Some(b) if b.is_ascii_whitespace() => {}
        _ => {
            return Err(r.err(
                r.at,
                "expected one whitespace byte after maxval, before the pixel data",
            ))
        }
    }
    let start = r.at + 1;
    let wide = maxval > 255;
    let need = count * if wide { 2 } else { 1 };
    let have = r.bytes.len().saturating_sub(start);
    if have < need {
        return Err(r.err(
            r.bytes.len(),
            format!("truncated: pixel data needs {need} bytes from byte {start}, the file has only {have}"),
        ));
    }
    let data = &r.bytes[start..start + need];
    let pixels: Vec<u16> = if wide {
        data.chunks_exact(2)
            .map(|c| u16::from_be_bytes([c[0], c[1]]))
            .collect()
    } else {
        data.iter().map(|&b| u16::from(b)).collect()
    };
    if let Some(i) = pixels.iter().position(|&p| p > maxval) {
        let at = start + i * if wide { 2 } else { 1 };
        return Err(r.err(
            at,
            format!("pixel value {} exceeds maxval {maxval}", pixels[i]),
        ));
    }
    let rest = start + need;
    let trailing = r.bytes[rest..]
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .map(|i| rest + i);
    Ok((pixels, trailing))
}

fn plain_pixels(
    r: &mut Reader<'_>,
    count: usize,
    maxval: u16,
) -> Result<(Vec<u16>, Option<usize>), ArenaError> {
    // Each value takes at least two bytes ("0 "), so a lying header cannot make us reserve more.
    let mut pixels = Vec::with_capacity(count.min(r.bytes.len() / 2 + 1));
    for i in 0..count {
        r.skip_space();
        if r.at >= r.bytes.len() {
            return Err(r.err(
                r.at,
                format!("truncated: expected {count} pixel values, found {i}"),
            ));
        }
        let (v, at) = r.number("pixel value")?;
        if v > u64::from(maxval) {
            return Err(r.err(at, format!("pixel value {v} exceeds maxval {maxval}")));
        }
        pixels.push(u16::try_from(v).unwrap_or(maxval));
    }
    r.skip_space();
    let trailing = (r.at < r.bytes.len()).then_some(r.at);
    Ok((pixels, trailing))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binary_and_plain_decode_the_same_image() {
        let p5 = decode(
            Path::new("a.pgm"),
            b"P5\n# c\n3 2\n255\n\x00\x7f\xff\x01\x02\x03",
        )
        .unwrap();
        let p2 = decode(
            Path::new("a.pgm"),
            b"P2 3 2 255\n0 127 255\n1 2 # note\n3\n",
        )
        .unwrap();
        assert_eq!(p5.pixels, vec![0, 127, 255, 1, 2, 3]);
        assert_eq!(p5, p2);
    }

    #[test]
    fn sixteen_bit_pixels_are_big_endian() {
        let p = decode(Path::new("a.pgm"), b"P5 2 1 1000 \x03\xe8\x00\x01").unwrap();
        assert_eq!(p.pixels, vec![1000, 1]);
    }

    #[test]
    fn truncated_binary_data_reports_the_end_offset() {
        let e = decode(Path::new("a.pgm"), b"P5 4 4 255\n\x00\x00")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("a.pgm: byte 13: truncated"), "{e}");
    }
}
