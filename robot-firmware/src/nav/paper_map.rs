//! Seed 004's arena as the planner's tests, benchmarks and the Cortex-M4 cost image all use
//! it: one copy.

/// `shared/data/arenas/ciberrato/wallsMicRato99.xml` rasterised at 17 x 17 (a cell is
/// obstacle when its centre is inside a wall), row 0 at the arena's y = 0; `#` a wall, `B`
/// the goal light, "marked as a regular obstacle" (seed 004 §6), `.` free.
pub const MICRO_RATO_99: [&str; 17] = [
    "...#.............",
    "...#.............",
    "...#.............",
    "...#.............",
    "...#...#####.#...",
    "...#...#.....#...",
    "...#...#.....#...",
    "...#...#.....#...",
    "...#...#..B......",
    ".......#.........",
    ".......#.....#...",
    ".......#.....#...",
    ".......#####.#...",
    ".................",
    ".................",
    ".................",
    ".................",
];
