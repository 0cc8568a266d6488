//! Parameter files: `name = value` lines, as `station params save` writes them and `load` and
//! `diff` read them (the shape of MAVProxy's `.parm` files, with names instead of ids).
//!
//! Layer: pure text <-> values, no I/O. Format (docs/station.md, "Parameter files"):
//! - one parameter a line: `NAME = VALUE`, white space around either side ignored;
//! - `#` starts a comment to the end of the line (save writes the unit, range and
//!   description there); blank lines are ignored;
//! - NAME is a name of the firmware's table (`robot_firmware::params::PARAMS`), VALUE a
//!   decimal number; each name at most once. The robot checks ranges, not the file.
//!
//! Invariants: a file is accepted whole or refused with the first fault as `FILE:LINE:COL:
//! what`, in time linear in its length; nothing from the file reaches a terminal unescaped
//! (the caller prints through `terminal_text`).

use robot_firmware::params::{by_name, ParamInfo};

use crate::format::{format_value, range_text};

/// One `name = value` line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Entry {
    pub info: &'static ParamInfo,
    pub value: f32,
    /// 1-based line number in the file.
    pub line: usize,
}

/// Longest file read, bytes: 31 parameters with long comments fit in a few KB.
pub const MAX_FILE_BYTES: usize = 256 * 1024;

/// What a parameter file may be (`input_file`'s rule).
pub const PARAMETER_FILE: crate::input_file::InputKind = crate::input_file::InputKind {
    what: "parameter files",
    max_bytes: MAX_FILE_BYTES as u64,
    pipes: false,
};

/// Parses a parameter file; `label` names it in errors (`robot.parm:3:1: ...`).
pub fn parse(label: &str, bytes: &[u8]) -> Result<Vec<Entry>, String> {
    if bytes.len() > MAX_FILE_BYTES {
        return Err(format!(
            "{label}: {} bytes; a parameter file is at most {MAX_FILE_BYTES} bytes",
            bytes.len()
        ));
    }
    let mut entries: Vec<Entry> = Vec::new();
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line = i + 1;
        let at = |col: usize, what: String| format!("{label}:{line}:{col}: {what}");
        let text = std::str::from_utf8(raw).map_err(|e| {
            at(
                e.valid_up_to() + 1,
                "not UTF-8 text; a parameter file is `name = value` lines".into(),
            )
        })?;
        let text = text.strip_suffix('\r').unwrap_or(text);
        let body = text.split('#').next().unwrap_or("");
        if body.trim().is_empty() {
            continue;
        }
        let col = |s: &str| s.as_ptr() as usize - text.as_ptr() as usize + 1;
        let Some((name, value)) = body.split_once('=') else {
            let start = body.trim_start();
            return Err(at(
                col(start),
                format!("expected `name = value`, found {:?}", start.trim_end()),
            ));
        };
        let name_t = name.trim();
        if name_t.is_empty() {
            return Err(at(
                col(body),
                "a parameter name is missing before `=`".into(),
            ));
        }
        let info = by_name(name_t)
            .ok_or_else(|| at(col(name.trim_start()), crate::param_names::unknown(name_t)))?;
        let value_t = value.trim();
        let vcol = if value_t.is_empty() {
            col(value)
        } else {
            col(value.trim_start())
        };
        let v: f32 = value_t
            .parse()
            .ok()
            .filter(|v: &f32| v.is_finite())
            .ok_or_else(|| {
                at(
                    vcol,
                    format!("{}: value {value_t:?} is not a finite number", info.name),
                )
            })?;
        if let Some(first) = entries.iter().find(|e| e.info.id == info.id) {
            return Err(at(
                col(name.trim_start()),
                format!("{} is set twice (first on line {})", info.name, first.line),
            ));
        }
        entries.push(Entry {
            info,
            value: v,
            line,
        });
    }
    Ok(entries)
}

/// The file `save` writes: a header comment, then one line per value, unit, range and
/// description in the line's comment.
pub fn format(header: &str, values: &[(&'static ParamInfo, f32)]) -> String {
    let mut out = String::new();
    for l in header.lines() {
        out.push_str("# ");
        out.push_str(l);
        out.push('\n');
    }
    out.push_str(
        "# name = value  # unit, range: description (docs/station.md, \"Parameter files\")\n",
    );
    for (info, v) in values {
        let unit = if info.unit.is_empty() {
            String::new()
        } else {
            format!("{}, ", info.unit)
        };
        out.push_str(&format!(
            "{} = {}  # {unit}{}: {}\n",
            info.name,
            // Shortest text that reads back as the same f32: a save loses nothing.
            format_value(*v),
            range_text(info),
            info.desc
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use robot_firmware::params::PARAMS;

    #[test]
    fn what_save_writes_load_reads_back() {
        let mut values: Vec<_> = PARAMS.iter().map(|p| (p, p.min)).collect();
        // More digits than the editor shows: the file keeps them all.
        values[6].1 = 0.012_345_67;
        let text = format("robot-firmware test\nprofile Khepera", &values);
        let back = parse("x.parm", text.as_bytes()).unwrap_or_default();
        assert_eq!(back.len(), PARAMS.len());
        for (e, (p, v)) in back.iter().zip(&values) {
            assert_eq!(e.info.id, p.id);
            assert_eq!(e.value, *v, "{}", p.name);
        }
    }

    #[test]
    fn faults_name_the_line_and_column() {
        let cases: [(&str, &str); 7] = [
            (
                "failsafe_ms = 300\nbogus = 1\n",
                "x:2:1: unknown parameter \"bogus\"",
            ),
            ("  failsafe_ms 300", "x:1:3: expected `name = value`"),
            (
                "failsafe_ms = abc",
                "x:1:15: failsafe_ms: value \"abc\" is not a finite",
            ),
            (
                "failsafe_ms =",
                "x:1:14: failsafe_ms: value \"\" is not a finite",
            ),
            ("failsafe_ms = inf", "not a finite number"),
            (
                "failsafe_ms = 1\n\n failsafe_ms = 2",
                "x:3:2: failsafe_ms is set twice (first on line 1)",
            ),
            (" = 2", "x:1:1: a parameter name is missing"),
        ];
        for (text, want) in cases {
            let e = parse("x", text.as_bytes()).err().unwrap_or_default();
            assert!(e.contains(want), "{text:?}: {e}");
        }
        let e = parse("x", b"failsafe_ms = 3\xff0")
            .err()
            .unwrap_or_default();
        assert!(e.starts_with("x:1:16: not UTF-8"), "{e}");
        assert_eq!(
            parse("x", b"# only a comment\r\n\r\nfailsafe_ms=400 # ms\r\n")
                .map(|v| v.iter().map(|e| e.value).collect::<Vec<_>>()),
            Ok(vec![400.0])
        );
    }
}
