//! JSON as the station and the emulator write it (`--json` reports, MCAP messages, files):
//! serde_json's, with every character [`crate::terminal_text::must_escape`] names written as a
//! JSON escape (`\u009b`, `\u007f`, `\u202e`).
//!
//! Layer: formatting, no I/O of its own. serde_json escapes the C0 controls, `"` and `\` and
//! copies every other character as it is, so a recording's header string holding CSI (U+009B)
//! reached the terminal raw from `station replay --json` (issue 31). Escaping is JSON's own: a
//! reader decodes the same string; only what a terminal would act on is never written raw.
//! What can fail: what serde_json's serializer fails on (a map with non-string keys).

use std::io;

use serde::Serialize;
use serde_json::ser::{CompactFormatter, Formatter, PrettyFormatter, Serializer};

use crate::terminal_text::must_escape;

/// `v` as indented JSON text (`serde_json::to_string_pretty`, escaped by the rule).
pub fn pretty<T: ?Sized + Serialize>(v: &T) -> serde_json::Result<String> {
    let mut out = Vec::with_capacity(128);
    write_with(&mut out, v, PrettyFormatter::new())?;
    Ok(text(out))
}

/// `v` as one line of JSON text (`serde_json::to_string`, escaped by the rule).
pub fn compact<T: ?Sized + Serialize>(v: &T) -> serde_json::Result<String> {
    let mut out = Vec::with_capacity(128);
    write(&mut out, v)?;
    Ok(text(out))
}

/// Appends `v` as one line of JSON to `out` (`serde_json::to_writer`, escaped by the rule).
pub fn write<W: io::Write, T: ?Sized + Serialize>(out: W, v: &T) -> serde_json::Result<()> {
    write_with(out, v, CompactFormatter)
}

/// Appends `v` as indented JSON to `out`.
pub fn write_pretty<W: io::Write, T: ?Sized + Serialize>(out: W, v: &T) -> serde_json::Result<()> {
    write_with(out, v, PrettyFormatter::new())
}

fn write_with<W: io::Write, T: ?Sized + Serialize, F: Formatter>(
    out: W,
    v: &T,
    f: F,
) -> serde_json::Result<()> {
    v.serialize(&mut Serializer::with_formatter(out, Escaping(f)))
}

/// serde_json writes only valid UTF-8 (and the escapes are ASCII).
fn text(bytes: Vec<u8>) -> String {
    String::from_utf8(bytes).unwrap_or_else(|e| String::from_utf8_lossy(e.as_bytes()).into_owned())
}

/// A formatter that lays JSON out as `F` does and escapes by the rule.
struct Escaping<F>(F);

/// `Formatter` methods that pass the writer (and their arguments) on to `F`'s.
macro_rules! delegate {
    ($($name:ident($($arg:ident: $ty:ty)?)),*) => {
        $(
            fn $name<W: ?Sized + io::Write>(&mut self, w: &mut W $(, $arg: $ty)?) -> io::Result<()> {
                self.0.$name(w $(, $arg)?)
            }
        )*
    };
}

impl<F: Formatter> Formatter for Escaping<F> {
    /// Runs of a string between serde_json's own escapes: here DEL, C1 controls and the
    /// bidirectional overrides (all below U+FFFF) become `\uXXXX`.
    fn write_string_fragment<W: ?Sized + io::Write>(
        &mut self,
        w: &mut W,
        fragment: &str,
    ) -> io::Result<()> {
        // Printable ASCII, nearly every string, needs no look at each character.
        if fragment.bytes().all(|b| (0x20..0x7f).contains(&b)) {
            return w.write_all(fragment.as_bytes());
        }
        let mut start = 0;
        for (i, c) in fragment.char_indices() {
            if must_escape(c) {
                w.write_all(&fragment.as_bytes()[start..i])?;
                write!(w, "\\u{:04x}", u32::from(c))?;
                start = i + c.len_utf8();
            }
        }
        w.write_all(&fragment.as_bytes()[start..])
    }

    // The layout is `F`'s.
    delegate!(
        begin_array(),
        end_array(),
        begin_array_value(first: bool),
        end_array_value(),
        begin_object(),
        end_object(),
        begin_object_key(first: bool),
        end_object_key(),
        begin_object_value(),
        end_object_value()
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn what_a_terminal_acts_on_is_escaped_and_the_json_reads_back_the_same() {
        let hostile = "port\u{9b}31m\u{1b}]0;x\u{7}\u{7f}\u{202e}é \"q\" \\";
        let v = serde_json::json!({"port": hostile, "n": [1, 2]});
        let one = compact(&v).expect("writes");
        assert_eq!(
            one,
            r#"{"n":[1,2],"port":"port\u009b31m\u001b]0;x\u0007\u007f\u202eé \"q\" \\"}"#
        );
        assert!(!one.chars().any(must_escape));
        let back: serde_json::Value = serde_json::from_str(&one).expect("reads");
        assert_eq!(back, v);
        // The layout is serde_json's, pretty or not.
        let clean = serde_json::json!({"a": {"b": [1, "x"]}});
        assert_eq!(
            pretty(&clean).expect("writes"),
            serde_json::to_string_pretty(&clean).expect("writes")
        );
        assert_eq!(
            compact(&clean).expect("writes"),
            serde_json::to_string(&clean).expect("writes")
        );
        let indented = pretty(&v).expect("writes");
        assert!(!indented.chars().any(|c| c != '\n' && must_escape(c)));
    }
}
