//! The arena drawn under the map: walls, targets and beacons in metres.
//!
//! Layer: app data converted once from an `emulator::arena::Arena` (the same importers the
//! emulator uses: CiberRato XML, micromouse mazes, ROS maps, ASCII grids), so the station
//! draws exactly the world the emulator simulates, or the one the operator names with
//! `--arena` for a real robot. Cannot fail once built; loading reports `ArenaError`s.

use emulator::arena::Arena;

/// What the map draws of an arena.
#[derive(Clone, Debug, PartialEq)]
pub struct ArenaOverlay {
    pub name: String,
    /// min x, min y, max x, max y, metres.
    pub bounds: [f64; 4],
    /// The bounds rectangle is itself a wall.
    pub enclosed: bool,
    /// Closed polygons.
    pub walls: Vec<Vec<(f64, f64)>>,
    /// Centre and radius.
    pub targets: Vec<((f64, f64), f64)>,
    pub beacons: Vec<(f64, f64)>,
    /// Light sources (seed 000: lamps the Khepera's ambient sensors see).
    pub lights: Vec<(f64, f64)>,
    /// The foraging site (seed 000 §7), when the arena has one.
    pub forage: Option<ForageOverlay>,
    /// The importer's warnings (file:line: what), shown in the log when the app starts.
    pub warnings: Vec<String>,
}

/// What the map draws of a foraging site: home base, objects where they start, landmarks.
#[derive(Clone, Debug, PartialEq)]
pub struct ForageOverlay {
    /// Home base centre and radius, metres.
    pub home: ((f64, f64), f64),
    /// Objects at their start, metres (one under each lamp).
    pub objects: Vec<(f64, f64)>,
    /// The three global landmarks, metres.
    pub landmarks: Vec<(f64, f64)>,
}

impl ForageOverlay {
    pub fn from_site(site: &emulator::forage::ForageSite) -> Self {
        ForageOverlay {
            home: ((site.home.centre.x, site.home.centre.y), site.home.radius_m),
            objects: site.object_positions().iter().map(|p| (p.x, p.y)).collect(),
            landmarks: site.landmarks.iter().map(|p| (p.x, p.y)).collect(),
        }
    }
}

impl ArenaOverlay {
    pub fn from_arena(a: &Arena) -> Self {
        ArenaOverlay {
            name: a.name.clone(),
            bounds: [
                a.bounds.min.x,
                a.bounds.min.y,
                a.bounds.max.x,
                a.bounds.max.y,
            ],
            enclosed: a.enclosed,
            walls: a
                .walls
                .iter()
                .map(|w| w.corners.iter().map(|p| (p.x, p.y)).collect())
                .collect(),
            targets: a
                .targets
                .iter()
                .map(|t| ((t.centre.x, t.centre.y), t.radius_m))
                .collect(),
            beacons: a
                .beacons
                .iter()
                .map(|b| (b.position.x, b.position.y))
                .collect(),
            lights: a
                .lights
                .iter()
                .map(|l| (l.position.x, l.position.y))
                .collect(),
            forage: emulator::forage::ForageSite::of_builtin(a)
                .map(|s| ForageOverlay::from_site(&s)),
            warnings: a.warnings.clone(),
        }
    }

    /// Loads an arena file with the emulator's importers.
    pub fn load(path: &std::path::Path) -> Result<Self, emulator::arena::ArenaError> {
        let a = emulator::arena::load(path, &emulator::arena::LoadOptions::default())?;
        Ok(Self::from_arena(&a))
    }
}
