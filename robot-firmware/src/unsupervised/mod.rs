//! Unsupervised landmarks and places (seed 003 ch. 3, Mächler 1998): the robot classifies its
//! raw sensor vectors online, picks "significant" classes, stores each with its context and the
//! odometric pose as a landmark, and resets its odometry to the stored pose when it meets the
//! same landmark again; sequences of landmarks become places recognised by Markov chains.
//!
//! Layer: pure computation, no I/O, no clock, `no_std` and heap-free; every store has a fixed
//! capacity given by a constant below, and a full store refuses (never overwrites, never
//! panics). Not wired into `Robot` yet: a profile composes it from [`classify`], [`landmarks`]
//! and [`places`] (docs/reproductions.md, the unsupervised places rows).
//!
//! - [`classify`]: growing K-means, ART-1, simplified Fuzzy ART (vigilance-tuned, §3.4).
//! - [`levenshtein`]: weighted Levenshtein distance over class labels (§3.7).
//! - [`landmarks`]: significant classes (§3.2.3), landmarks and odometry reset (§3.6-3.7.8).
//! - [`places`]: Markov-chain places over the landmark stream (§3.11).
//! - [`fusion`]: the position's variance and how far a match moves it (§3.15.2's bound).

pub mod classify;
pub mod fusion;
pub mod landmarks;
pub mod levenshtein;
pub mod places;

/// Largest input dimension a classifier accepts (8 IR + 8 light + compass + camera features
/// fit with room to spare).
pub const MAX_DIM: usize = 32;
/// Classes (output neurons) per classifier. A full classifier assigns the nearest class.
pub const MAX_CLASSES: usize = 64;
/// Class streams a landmark holds (one per classifier).
pub const STREAMS: usize = 3;
/// Labels before and after the kernel in a landmark (§3.6: "fifteen former and fifteen future").
pub const CONTEXT: usize = 15;
/// Labels per stream in a landmark: 15 + kernel + 15.
pub const WINDOW: usize = 2 * CONTEXT + 1;
/// Landmarks the store holds (the thesis's arena gave about 150; 300 "contained").
pub const MAX_LANDMARKS: usize = 320;
/// Places the place store holds (the thesis's arena gave about 40).
pub const MAX_PLACES: usize = 64;
/// Explicit (seen) transitions per place; unseen ones share the row's base probability.
pub const MAX_TRANSITIONS: usize = 48;
/// Landmarks in one place sequence.
pub const MAX_SEQUENCE: usize = 24;

#[cfg(test)]
mod tests {
    extern crate std;

    /// Prints the module's memory (docs/reproductions.md quotes it) and keeps the
    /// whole inside the 128 KB budget stated there.
    #[test]
    fn memory_budget() {
        use core::mem::size_of;
        let parts = [
            (
                "growing K-means",
                size_of::<super::classify::GrowingKMeans>(),
            ),
            ("ART-1", size_of::<super::classify::Art1>()),
            ("Fuzzy ART", size_of::<super::classify::FuzzyArt>()),
            (
                "landmark store",
                size_of::<super::landmarks::LandmarkStore>(),
            ),
            ("places", size_of::<super::places::Places>()),
        ];
        let total: usize = parts.iter().map(|p| p.1).sum();
        std::eprintln!("{parts:?} total {total}");
        assert!(total <= 128 * 1024, "{total}");
    }
}
