//! Text from the wire or from a file, made safe to print on a terminal: the one place that
//! decides which characters may reach it ([`must_escape`]), for the station and the emulator.
//!
//! Layer: pure functions. A robot's firmware name, its log lines, a recording's metadata, an
//! arena's name or a file's content quoted in an error are untrusted; printed raw, `ESC ] 0;
//! ... BEL` retitles the terminal, `ESC [2J` clears it, and worse sequences exist. Every
//! control character (C0 including ESC and BEL, DEL, C1) and every bidirectional-override
//! character (which reorders what is shown) becomes a visible escape such as `\x1b` or
//! `\u{202e}`, so the text stays readable and the fault visible. The link machine applies
//! `printable` to what it takes from the robot (so the TUI and every command get clean peer
//! names and log lines; ratatui also drops control characters when it draws); the commands
//! apply `printable_text` to what they print. JSON output goes through `json_text`, which
//! writes the same characters as JSON escapes (`\u009b`): serde_json escapes only C0, and
//! DEL or a C1 control such as CSI (U+009B) reached the terminal raw (issue 31).

use std::borrow::Cow;
use std::fmt::Write as _;

/// Whether `c` must not reach a terminal as it is: the rule every text output follows.
pub fn must_escape(c: char) -> bool {
    c.is_control()
        || matches!(c, '\u{200e}' | '\u{200f}' | '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}')
}

fn escape(s: &str, keep: impl Fn(char) -> bool) -> Cow<'_, str> {
    if !s.chars().any(|c| must_escape(c) && !keep(c)) {
        return Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        if !must_escape(c) || keep(c) {
            out.push(c);
        } else if (c as u32) < 0x100 {
            let _ = write!(out, "\\x{:02x}", c as u32);
        } else {
            let _ = write!(out, "\\u{{{:x}}}", c as u32);
        }
    }
    Cow::Owned(out)
}

/// One field (a name, a log line): every control character escaped, line breaks included,
/// so one field cannot pose as several lines.
pub fn printable(s: &str) -> Cow<'_, str> {
    escape(s, |_| false)
}

/// A whole report or message of our own making that quotes untrusted text: line breaks and
/// tabs stay, every other control character is escaped.
pub fn printable_text(s: &str) -> Cow<'_, str> {
    escape(s, |c| c == '\n' || c == '\t')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escape_sequences_become_visible_and_clean_text_is_untouched() {
        let hostile = "fw\u{1b}]0;owned\u{7}\u{1b}[2J\u{9b}31m\u{202e}gnp.exe\u{7f}";
        assert_eq!(
            printable(hostile),
            "fw\\x1b]0;owned\\x07\\x1b[2J\\x9b31m\\u{202e}gnp.exe\\x7f"
        );
        assert!(matches!(
            printable("robot-firmware 0.1 é"),
            Cow::Borrowed(_)
        ));
        assert_eq!(printable("a\nb\tc\r"), "a\\x0ab\\x09c\\x0d");
        assert_eq!(printable_text("a\nb\tc\r\u{1b}"), "a\nb\tc\\x0d\\x1b");
    }
}
