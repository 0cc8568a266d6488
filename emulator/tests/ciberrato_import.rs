//! The CiberRato importer reads labs as the CiberRato simulator does (cblabhandler.cpp,
//! cbwall.cpp, cbgridhandler.cpp): `<Row Pattern>` mazes whose walls block the robot, every
//! beacon and target, repeated corners, grid files under the names real competitions used,
//! and warnings that are counted, not located one by one.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};

use emulator::arena::ciberrato::{find_grid, parse_lab, row_walls, MAX_WARNINGS};
use emulator::arena::{load, LoadOptions, CIBERRATO_UNIT_M};
use emulator::geometry::Point;
use emulator::scenarios::task::{run_scenario, GoalPoint, ScenarioOptions, Task};
use emulator::world::World;
use robot_firmware::MICRO_RATO;

const U: f64 = CIBERRATO_UNIT_M;

/// A 14 x 4 unit lab cut in two by a `<Row>` wall at x = 6 units, full height.
const ROW_LAB: &str = r#"<Lab Name="rows" Width="14" Height="4">
  <Beacon X="10" Y="2" Height="2"/>
  <Target X="10" Y="2" Radius="1"/>
  <Row Pos="2" Pattern="        |     "/>
  <Row Pos="1" Pattern="               "/>
  <Row Pos="0" Pattern="        |     "/>
</Lab>"#;

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("ciberrato-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn row_pattern_walls_are_where_the_simulator_puts_them() {
    // Even row: '|' at column 8 is the wall right of cell 2, x = 2 * 9 / 3 = 6, y 2..4.
    let (v, _) = row_walls(2, "        |", 28.0);
    assert_eq!(v.len(), 1);
    assert!((v[0].min.x - 5.9).abs() < 1e-9 && (v[0].max.x - 6.1).abs() < 1e-9);
    assert!((v[0].min.y - 2.0).abs() < 1e-9 && (v[0].max.y - 4.0).abs() < 1e-9);
    // Odd row: '-' runs on cell columns; "--+--+  +--" is a wall over cells 0..1 and one over
    // cell 3, at y = pos + 1 = 4, 0.1 either side. '+' and other characters do nothing.
    let (h, open) = row_walls(3, "--+--+  +--", 28.0);
    assert!(open, "the last run reaches the pattern's end");
    assert_eq!(h.len(), 2);
    assert!((h[0].min.x - 0.0).abs() < 1e-9 && (h[0].max.x - 4.0).abs() < 1e-9);
    assert!((h[0].min.y - 3.9).abs() < 1e-9 && (h[0].max.y - 4.1).abs() < 1e-9);
    assert!((h[1].min.x - 6.0).abs() < 1e-9 && (h[1].max.x - 8.0).abs() < 1e-9);
    // The simulator's 28-unit labs end a run at column 39, the 14th cell.
    let full = format!("{}  ", "-".repeat(40));
    let (h, open) = row_walls(1, &full, 28.0);
    assert!(!open);
    assert_eq!(h.len(), 1);
    assert!((h[0].max.x - 28.0).abs() < 1e-9);
}

#[test]
fn a_row_pattern_lab_has_its_walls() {
    let a = parse_lab(Path::new("rows.xml"), ROW_LAB, U).unwrap();
    assert_eq!(a.walls.len(), 2, "{:?}", a.warnings);
    assert!(a.warnings.is_empty(), "{:?}", a.warnings);
    assert!(a.is_solid(Point::new(6.0 * U, 1.0 * U)));
    assert!(a.is_solid(Point::new(6.0 * U, 3.0 * U)));
    assert!(!a.is_solid(Point::new(4.0 * U, 3.0 * U)));
    // Row walls are CiberRato's default 4 units high.
    assert_eq!(a.walls[0].height_m, Some(4.0 * U));
}

#[test]
fn a_row_pattern_wall_blocks_the_robot() {
    // Before, <Row> was an unknown element: the robot drove through an empty box to the goal.
    let a = parse_lab(Path::new("rows.xml"), ROW_LAB, U).unwrap();
    let mut opts = ScenarioOptions::new(
        &MICRO_RATO,
        Task::GoTo(Some(GoalPoint {
            x_m: 10.0 * U,
            y_m: 2.0 * U,
        })),
    );
    opts.seed = 1;
    opts.timeout_s = 30.0;
    opts.start = Some(emulator::arena::Pose {
        x: 2.0 * U,
        y: 2.0 * U,
        heading: 0.0,
    });
    let r = run_scenario(a, opts).unwrap();
    assert!(!r.reached, "{r:?}");
    assert!(r.final_true.x_m < 5.9 * U, "{r:?}");
}

#[test]
fn a_repeated_corner_is_dropped_with_a_warning() {
    let xml = r#"<Lab Width="10" Height="10">
  <Wall Height="1">
    <Corner X="1" Y="1"/><Corner X="3" Y="1"/><Corner X="3" Y="1"/>
    <Corner X="3" Y="3"/><Corner X="1" Y="3"/><Corner X="1" Y="1"/>
  </Wall>
</Lab>"#;
    let a = parse_lab(Path::new("rep.xml"), xml, 1.0).unwrap();
    assert_eq!(a.walls[0].corners.len(), 4);
    assert_eq!(a.warnings.len(), 2, "{:?}", a.warnings);
    assert!(
        a.warnings[0].starts_with("rep.xml:3:47: corner (3, 1) repeats"),
        "{:?}",
        a.warnings
    );
    // Repeats do not count towards the 3 corners a wall needs.
    let two = r#"<Lab Width="10" Height="10"><Wall><Corner X="1" Y="1"/><Corner X="1" Y="1"/>
      <Corner X="2" Y="2"/></Wall></Lab>"#;
    let e = parse_lab(Path::new("two.xml"), two, 1.0).unwrap_err();
    assert!(
        e.to_string().contains("this one has 2 besides repeats"),
        "{e}"
    );
}

#[test]
fn every_beacon_and_target_is_kept_and_the_search_ends_in_a_beaconed_target() {
    // CiberRato 2011's final: the beacon's target, and the start area as a second target.
    let xml = r#"<Lab Width="28" Height="14">
  <Beacon X="24" Y="3" Height="2"/><Beacon X="4" Y="11" Height="2"/>
  <Target X="24" Y="3" Radius="2"/><Target X="3" Y="2.5" Radius="2"/>
  <Target X="4" Y="11" Radius="1"/>
</Lab>"#;
    let a = parse_lab(Path::new("m.xml"), xml, U).unwrap();
    assert_eq!((a.beacons.len(), a.targets.len()), (2, 3));
    let w = World::new(a, Vec::new(), None).unwrap();
    assert_eq!(w.beacons().len(), 2);
    assert_eq!(w.goal_targets().count(), 2);
    assert!(
        w.in_target(Point::new(4.0 * U, 11.0 * U)),
        "second beacon's area"
    );
    assert!(w.in_target(Point::new(24.0 * U, 3.0 * U)));
    assert!(
        !w.in_target(Point::new(3.0 * U, 2.5 * U)),
        "the start area is no goal"
    );
}

#[test]
fn the_beacon_sensor_tells_several_beacons_apart_as_ciberrato_does() {
    use emulator::rng::SimRng;
    use emulator::sensors::rato::BeaconSensor;
    let xml = r#"<Lab Width="28" Height="14">
  <Beacon X="20" Y="7" Height="2"/><Beacon X="8" Y="7" Height="2"/>
</Lab>"#;
    let w = World::new(
        parse_lab(Path::new("b.xml"), xml, U).unwrap(),
        Vec::new(),
        None,
    )
    .unwrap();
    let mut s = BeaconSensor::new(true, 0.0, 0.0, SimRng::new(1, 7));
    let pose = |heading| emulator::arena::Pose {
        x: 12.0 * U,
        y: 7.0 * U,
        heading,
    };
    // Facing +x, beacon 0 (the far one) in view; facing -x only beacon 1 (the near one) is:
    // channel 0 reads nothing there, however strong beacon 1 is (CiberRato's
    // GetBeaconSensor(id); a receiver locked on the strongest read beacon 1 as the goal).
    let (east, west) = (pose(0.0), pose(std::f64::consts::PI));
    let goal_east = s.read_channel(w.beacons(), 0, &[], east).unwrap();
    let goal_west = s.read_channel(w.beacons(), 0, &[], west).unwrap();
    let other_west = s.read_channel(w.beacons(), 1, &[], west).unwrap();
    assert!(goal_east.strength > 0, "{goal_east:?}");
    assert_eq!(goal_west.strength, 0, "{goal_west:?}");
    assert!(other_west.strength > goal_east.strength, "{other_west:?}");
    assert_eq!(
        s.read_channel(w.beacons(), 2, &[], west).unwrap().strength,
        0
    );
}

#[test]
fn grid_files_are_found_under_the_names_competitions_used() {
    let d = temp_dir("grids");
    let lab = r#"<Lab Width="28" Height="14"/>"#;
    let grid = r#"<Grid><Position X="3" Y="2" Dir="90"/></Grid>"#;
    for f in [
        "Ciber2011-final-lab.xml",
        "Ciber2011-final-grd.xml",
        "ciber2002Lab1.xml",
        "ciber2002Grid1.xml",
        "Ciber2003_Manga1Lab.xml",
        "Ciber2003_manga1Grid.xml",
        "Ciber2001Final.xml",
        "Ciber2001Grid.xml",
        "Ciber2011-m2-lab.xml",
    ] {
        let text = if f.contains("rid") || f.contains("grd") {
            grid
        } else {
            lab
        };
        std::fs::write(d.join(f), text).unwrap();
    }
    for (l, g) in [
        ("Ciber2011-final-lab.xml", "Ciber2011-final-grd.xml"),
        ("ciber2002Lab1.xml", "ciber2002Grid1.xml"),
        ("Ciber2003_Manga1Lab.xml", "Ciber2003_manga1Grid.xml"),
        ("Ciber2001Final.xml", "Ciber2001Grid.xml"),
    ] {
        let found = find_grid(&d.join(l));
        assert_eq!(found.path, Some(d.join(g)), "{l}");
        let a = load(&d.join(l), &LoadOptions::default()).unwrap();
        assert_eq!(a.starts.len(), 1, "{l}");
    }
    // The usual name needs no word; the others say which file was taken.
    assert!(find_grid(&d.join("ciber2002Lab1.xml")).note.is_none());
    assert!(find_grid(&d.join("Ciber2003_Manga1Lab.xml"))
        .note
        .is_some_and(|n| n.contains("Ciber2003_manga1Grid.xml")));
    // A lab named as one but with no grid: no start poses, and a warning that says so.
    let a = load(&d.join("Ciber2011-m2-lab.xml"), &LoadOptions::default()).unwrap();
    assert!(a.starts.is_empty());
    assert!(
        a.warnings.iter().any(|w| w.contains("no grid file found")),
        "{:?}",
        a.warnings
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn many_unknown_elements_keep_a_few_located_warnings_and_count_the_rest() {
    let n = 5000;
    let xml = format!(
        "<Lab Width=\"10\" Height=\"10\">\n{}</Lab>\n",
        "<Decoration />\n".repeat(n)
    );
    let a = parse_lab(Path::new("u.xml"), &xml, 1.0).unwrap();
    assert_eq!(a.warnings.len(), MAX_WARNINGS + 1);
    assert!(a.warnings[0].starts_with("u.xml:2:1: unknown element 'Decoration'"));
    assert_eq!(
        a.warnings[MAX_WARNINGS],
        format!("u.xml: {} more warnings not shown", n - MAX_WARNINGS)
    );
}

#[test]
fn warnings_never_carry_control_characters() {
    let xml = "<Lab Width=\"10\" Height=\"10\"><Row Pos=\"0\"/><Odd a=\"x\"/></Lab>";
    let a = parse_lab(Path::new("c\u{7}.xml"), xml, 1.0).unwrap();
    assert!(!a.warnings.is_empty());
    assert!(a.warnings.iter().all(|w| !w.chars().any(char::is_control)));
}
