//! Netpbm greyscale images: binary P5 and plain (ASCII) P2, 8- or 16-bit, for ROS maps.
//!
//! Layer: a decoder under [`super::rosmap`]; bytes in, pixels out, no I/O.
//! [`header`] reads only the magic and the three numbers, so a caller can refuse a size from
//! the first bytes of the file; [`decode`] hands each pixel to a sink (row-major, top row
//! first, each <= `maxval`) instead of building a pixel array: the caller stores what it needs
//! (a cell byte), so memory stays at the file plus one byte a pixel.
//! What can fail: a wrong magic (PNG, PBM, PPM are named as such), header numbers missing,
//! zero, or past [`MAX_GRID_SIDE`], maxval outside 1..=65535, truncated pixel data, a pixel above
//! maxval. P5 errors give the byte offset; P2 errors give line:column.

use std::path::Path;

use super::error::{to_u32, ArenaError, Position};
use super::MAX_GRID_SIDE;

/// A PGM's header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Header {
    pub width: u32,
    pub height: u32,
    pub maxval: u16,
    /// Plain (P2, text) rather than binary (P5) pixels.
    plain: bool,
    /// Offset just past maxval.
    end: usize,
}

/// What [`decode`] found besides the pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Decoded {
    pub header: Header,
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

/// Reads a P5 or P2 PGM's header (magic, width, height, maxval) and checks its numbers.
pub(crate) fn header(path: &Path, bytes: &[u8]) -> Result<Header, ArenaError> {
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
    Ok(Header {
        width: to_u32(w as usize),
        height: to_u32(h as usize),
        maxval: u16::try_from(maxval).unwrap_or(u16::MAX),
        plain,
        end: r.at,
    })
}

impl Header {
    /// False when `len` bytes cannot hold this image's pixels (P5: one or two bytes each; P2:
    /// a digit and a separator each), so that a lying header is refused before the caller
    /// allocates its grid.
    pub fn fits(&self, len: usize) -> bool {
        let count = self.width as usize * self.height as usize;
        let each = match (self.plain, self.maxval > 255) {
            (true, _) => 2,
            (false, true) => 2,
            (false, false) => 1,
        };
        let data = len.saturating_sub(self.end + 1);
        data + usize::from(self.plain) >= count * each
    }
}

/// Decodes a P5 or P2 PGM, giving `sink` each pixel's index (row-major, top row first) and
/// value.
pub(crate) fn decode(
    path: &Path,
    bytes: &[u8],
    sink: impl FnMut(usize, u16),
) -> Result<Decoded, ArenaError> {
    let header = header(path, bytes)?;
    let mut r = Reader {
        path,
        bytes,
        at: header.end,
        plain: header.plain,
    };
    let count = header.width as usize * header.height as usize;
    let trailing = if header.plain {
        plain_pixels(&mut r, count, header.maxval, sink)?
    } else {
        binary_pixels(&r, count, header.maxval, sink)?
    };
    Ok(Decoded { header, trailing })
}

fn binary_pixels(
    r: &Reader<'_>,
    count: usize,
    maxval: u16,
    mut sink: impl FnMut(usize, u16),
) -> Result<Option<usize>, ArenaError> {
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
    let size = if wide { 2 } else { 1 };
    for (i, c) in data.chunks_exact(size).enumerate() {
        let p = match *c {
            [hi, lo] => u16::from_be_bytes([hi, lo]),
            [b] => u16::from(b),
            _ => 0,
        };
        if p > maxval {
            return Err(r.err(
                start + i * size,
                format!("pixel value {p} exceeds maxval {maxval}"),
            ));
        }
        sink(i, p);
    }
    let rest = start + need;
    let trailing = r.bytes[rest..]
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .map(|i| rest + i);
    Ok(trailing)
}

fn plain_pixels(
    r: &mut Reader<'_>,
    count: usize,
    maxval: u16,
    mut sink: impl FnMut(usize, u16),
) -> Result<Option<usize>, ArenaError> {
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
        sink(i, u16::try_from(v).unwrap_or(maxval));
    }
    r.skip_space();
    let trailing = (r.at < r.bytes.len()).then_some(r.at);
    Ok(trailing)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pixels(bytes: &[u8]) -> Result<(Header, Vec<u16>), ArenaError> {
        let mut out = Vec::new();
        let d = decode(Path::new("a.pgm"), bytes, |i, p| {
            assert_eq!(i, out.len());
            out.push(p);
        })?;
        Ok((d.header, out))
    }

    #[test]
    fn binary_and_plain_decode_the_same_image() {
        let (h5, p5) = pixels(b"P5\n# c\n3 2\n255\n\x00\x7f\xff\x01\x02\x03").unwrap();
        let (h2, p2) = pixels(b"P2 3 2 255\n0 127 255\n1 2 # note\n3\n").unwrap();
        assert_eq!(p5, vec![0, 127, 255, 1, 2, 3]);
        assert_eq!(p5, p2);
        assert_eq!(
            (h5.width, h5.height, h5.maxval),
            (h2.width, h2.height, h2.maxval)
        );
    }

    #[test]
    fn sixteen_bit_pixels_are_big_endian() {
        let (_, p) = pixels(b"P5 2 1 1000 \x03\xe8\x00\x01").unwrap();
        assert_eq!(p, vec![1000, 1]);
    }

    #[test]
    fn the_header_alone_gives_the_size() {
        let h = header(Path::new("a.pgm"), b"P5 8192 8192 255\n").unwrap();
        assert_eq!((h.width, h.height, h.maxval), (8192, 8192, 255));
        assert!(!h.fits(17));
    }

    #[test]
    fn fits_is_exact_for_the_smallest_images() {
        for (bytes, ok) in [
            (&b"P5 2 1 255\n\x00\x01"[..], true),
            (b"P5 2 1 255\n\x00", false),
            (b"P5 1 1 1000\n\x00\x01", true),
            (b"P5 1 1 1000\n\x00", false),
            (b"P2 2 1 255\n0 1", true),
            (b"P2 2 1 255\n0 ", false),
        ] {
            let h = header(Path::new("a.pgm"), bytes).unwrap();
            assert_eq!(
                h.fits(bytes.len()),
                ok,
                "{:?}",
                String::from_utf8_lossy(bytes)
            );
            assert_eq!(pixels(bytes).is_ok(), ok);
        }
    }

    #[test]
    fn truncated_binary_data_reports_the_end_offset() {
        let e = pixels(b"P5 4 4 255\n\x00\x00").unwrap_err().to_string();
        assert!(e.starts_with("a.pgm: byte 13: truncated"), "{e}");
    }
}
