//! Parameters as users name them: by name or id, and, for a name that is none, the closest
//! names. Every place a user names a parameter (`station send param`, `station params`,
//! `--param NAME=VALUE` of `retrace` and `replay`, parameter files) finds it here, so a typo
//! gets the same suggestion everywhere.
//!
//! Layer: pure, over the firmware's parameter table (`robot_firmware::params::PARAMS`).

use robot_firmware::params::{by_name, info, ParamInfo, PARAMS};

/// Most names suggested.
const MOST_SUGGESTED: usize = 3;

/// The parameter called `name`, or with the id `name` (decimal); else why not, with the
/// closest names: `unknown parameter "wheel_distance_mm"; did you mean
/// odo_wheel_distance_mm?`.
pub fn find(name: &str) -> Result<&'static ParamInfo, String> {
    let t = name.trim();
    by_name(t)
        .or_else(|| t.parse::<u16>().ok().and_then(info))
        .ok_or_else(|| unknown(t))
}

/// The message for a name that is no parameter.
pub fn unknown(name: &str) -> String {
    let shown = crate::terminal_text::printable(name);
    let close = closest(name);
    if close.is_empty() {
        format!("unknown parameter {shown:?} (`station params --port P list` lists them)")
    } else {
        format!(
            "unknown parameter {shown:?}; did you mean {}?",
            close.join(", ")
        )
    }
}

/// The names nearest `name`, nearest first: those containing it (or a word of it), then those
/// a few edits away (Levenshtein distance at most a third of the name, and at least 2).
pub fn closest(name: &str) -> Vec<&'static str> {
    let want = name.trim().to_lowercase();
    if want.is_empty() {
        return Vec::new();
    }
    let limit = (want.chars().count() / 3).max(2);
    let mut scored: Vec<(usize, &'static str)> = PARAMS
        .iter()
        .filter_map(|p| {
            let d = distance(&want, p.name);
            // Containing it is as good as one edit: `wheel_distance_mm` in
            // `odo_wheel_distance_mm` is the name with its group left off.
            let score = if p.name.contains(want.as_str()) {
                d.min(1)
            } else {
                d
            };
            (score <= limit).then_some((score, p.name))
        })
        .collect();
    scored.sort();
    scored
        .into_iter()
        .take(MOST_SUGGESTED)
        .map(|(_, n)| n)
        .collect()
}

/// Levenshtein distance between `a` and `b`, in characters.
fn distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row.first().copied().unwrap_or(0);
        if let Some(first) = row.first_mut() {
            *first = i + 1;
        }
        for (j, cb) in b.iter().enumerate() {
            let above = row.get(j + 1).copied().unwrap_or(0);
            let left = row.get(j).copied().unwrap_or(0);
            let cost = usize::from(ca != *cb);
            let v = (prev + cost).min(above + 1).min(left + 1);
            prev = above;
            if let Some(cell) = row.get_mut(j + 1) {
                *cell = v;
            }
        }
    }
    row.last().copied().unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_ids_are_found() {
        assert_eq!(find("failsafe_ms").map(|p| p.id), Ok(0));
        assert_eq!(find(" 5 ").map(|p| p.name), Ok("odo_wheel_distance_mm"));
    }

    #[test]
    fn a_name_without_its_group_or_with_a_typo_suggests_the_parameter() {
        let e = find("wheel_distance_mm").unwrap_err();
        assert!(e.contains("did you mean odo_wheel_distance_mm"), "{e}");
        let e = find("telemetry_hs").unwrap_err();
        assert!(e.contains("did you mean telemetry_hz"), "{e}");
        assert_eq!(closest("FAILSAFE_MS"), ["failsafe_ms"]);
    }

    #[test]
    fn nothing_close_says_where_the_names_are() {
        let e = find("warp_factor").unwrap_err();
        assert!(e.contains("unknown parameter \"warp_factor\""), "{e}");
        assert!(e.contains("station params --port P list"), "{e}");
    }

    #[test]
    fn distance_counts_edits() {
        assert_eq!(distance("kitten", "sitting"), 3);
        assert_eq!(distance("", "abc"), 3);
        assert_eq!(distance("abc", "abc"), 0);
    }
}
