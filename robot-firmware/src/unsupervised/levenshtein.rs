//! Weighted Levenshtein distance (§3.7.4, the thesis's "flat" algorithm) over short label
//! strings, with caller-given costs: §3.7.6 makes the substitution cost the distance of the two
//! classes' prototypes instead of a constant.
//!
//! Heap-free: two rows of `WINDOW + 1` cells; strings longer than `WINDOW` are refused.

use super::WINDOW;

/// The costs of the three edit operations.
pub trait EditCosts<T> {
    /// Cost of deleting `a` from the first string.
    fn delete(&self, a: &T) -> f32;
    /// Cost of inserting `b` from the second string.
    fn insert(&self, b: &T) -> f32;
    /// Cost of replacing `a` by `b` (0 when they are equal, normally).
    fn replace(&self, a: &T, b: &T) -> f32;
}

/// Unit costs: the plain Levenshtein distance.
pub struct Unit;

impl<T: PartialEq> EditCosts<T> for Unit {
    fn delete(&self, _: &T) -> f32 {
        1.0
    }
    fn insert(&self, _: &T) -> f32 {
        1.0
    }
    fn replace(&self, a: &T, b: &T) -> f32 {
        if a == b {
            0.0
        } else {
            1.0
        }
    }
}

/// The minimum total cost to turn `a` into `b`, or `None` if either is longer than `WINDOW`.
pub fn weighted<T, C: EditCosts<T>>(a: &[T], b: &[T], costs: &C) -> Option<f32> {
    if a.len() > WINDOW || b.len() > WINDOW {
        return None;
    }
    // Row x of the thesis's matrix M, kept as two rows: prev = M(x-1, .), cur = M(x, .).
    let mut prev = [0.0f32; WINDOW + 1];
    let mut cur = [0.0f32; WINDOW + 1];
    for (y, bj) in b.iter().enumerate() {
        prev[y + 1] = prev[y] + costs.insert(bj);
    }
    for ai in a {
        cur[0] = prev[0] + costs.delete(ai);
        for (y, bj) in b.iter().enumerate() {
            let m1 = prev[y] + costs.replace(ai, bj);
            let m2 = prev[y + 1] + costs.delete(ai);
            let m3 = cur[y] + costs.insert(bj);
            cur[y + 1] = m1.min(m2).min(m3);
        }
        prev[..=b.len()].copy_from_slice(&cur[..=b.len()]);
    }
    Some(prev[b.len()])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thesis_examples() {
        // §3.7.2 and Table 3-3.
        assert_eq!(weighted(b"ec", b"fc", &Unit), Some(1.0));
        assert_eq!(weighted(b"STEPHAN", b"STEFANIE", &Unit), Some(4.0));
        assert_eq!(weighted(b"", b"abc", &Unit), Some(3.0));
        assert_eq!(weighted(b"abc", b"", &Unit), Some(3.0));
    }

    struct Half;
    impl EditCosts<u8> for Half {
        fn delete(&self, _: &u8) -> f32 {
            1.0
        }
        fn insert(&self, _: &u8) -> f32 {
            1.0
        }
        fn replace(&self, a: &u8, b: &u8) -> f32 {
            if a == b {
                0.0
            } else {
                0.25
            }
        }
    }

    #[test]
    fn substitution_cost_is_the_callers() {
        // Cheap replacements win over delete + insert.
        assert_eq!(weighted(b"ab", b"cd", &Half), Some(0.5));
    }

    #[test]
    fn too_long_is_refused() {
        let long = [0u8; WINDOW + 1];
        assert_eq!(weighted(&long, b"a", &Unit), None);
    }
}
