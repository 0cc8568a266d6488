//! Where a run starts (issue 32, item 4): a lab's start poses come from the grid file the
//! CiberRato simulator would pair with it (a parameter file's `Lab`/`Grid`, else the names
//! competitions used); a lab with none starts where the robot can reach the goal, or the run
//! is refused saying why; a start inside a target the search may end in is reported as such
//! and never counted as reached.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::PathBuf;

use emulator::arena::ciberrato::find_grid;
use emulator::arena::{load, Arena, LoadOptions, CIBERRATO_UNIT_M};
use emulator::geometry::Point;
use emulator::scenarios::bench::{resolve_arenas, ArenaSource};
use emulator::scenarios::task::{run_scenario, ScenarioOptions, Task};
use emulator::sim::{start_pose, SimError};
use emulator::world::World;
use robot_firmware::MICRO_RATO;

const U: f64 = CIBERRATO_UNIT_M;

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("starts-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn a_parameter_file_pairs_a_lab_with_its_grid_as_the_simulator_does() {
    let d = temp_dir("params");
    std::fs::write(d.join("C1-lab.xml"), r#"<Lab Width="28" Height="14"/>"#).unwrap();
    // The name rules alone would take C1-grid.xml; the parameter file says startsC1.xml.
    let grid = r#"<Grid><Position X="3" Y="2" Dir="90"/></Grid>"#;
    std::fs::write(d.join("C1-grid.xml"), grid).unwrap();
    std::fs::write(
        d.join("startsC1.xml"),
        r#"<Grid><Position X="5" Y="4" Dir="0"/></Grid>"#,
    )
    .unwrap();
    // Paths as competitions ship them: relative to the simulator's folder.
    std::fs::write(
        d.join("C1-config.xml"),
        r#"<?xml version="1.0"?>
<Parameters SimTime="1800" CycleTime="50"
        Lab="../Labs/c1/C1-lab.xml"
        Grid="../Labs/c1/startsC1.xml"/>"#,
    )
    .unwrap();
    let found = find_grid(&d.join("C1-lab.xml"));
    assert_eq!(found.path, Some(d.join("startsC1.xml")));
    assert!(found.note.unwrap().contains("parameter file"));
    let a = load(&d.join("C1-lab.xml"), &LoadOptions::default()).unwrap();
    assert!((a.starts[0].x - 5.0 * U).abs() < 1e-9, "{:?}", a.starts);
    // A folder of labs for `bench --arenas DIR`: grid and parameter files are not arenas,
    // whatever their names.
    let labs = resolve_arenas(
        &[d.to_string_lossy().into_owned()],
        emulator::arena_gen::Kind::RealLike,
    )
    .unwrap();
    assert_eq!(
        labs,
        vec![ArenaSource::Named(
            d.join("C1-lab.xml").to_string_lossy().into_owned()
        )]
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// A 10 x 6 unit lab whose lower-left corner is a sealed 3 x 2 pocket, the goal at the right
/// (with `sealed_goal`, boxed in with its area).
fn lab_with_pocket(sealed_goal: bool) -> Arena {
    let d = temp_dir(if sealed_goal { "sealed" } else { "pocket" });
    // A box round the goal area, too small for a start outside it.
    let ring = if sealed_goal {
        r#"<Wall Height="1"><Corner X="7" Y="1.5"/><Corner X="10" Y="1.5"/><Corner X="10" Y="1.8"/><Corner X="7" Y="1.8"/></Wall>
  <Wall Height="1"><Corner X="7" Y="4.2"/><Corner X="10" Y="4.2"/><Corner X="10" Y="4.5"/><Corner X="7" Y="4.5"/></Wall>
  <Wall Height="1"><Corner X="7" Y="1.5"/><Corner X="7.3" Y="1.5"/><Corner X="7.3" Y="4.5"/><Corner X="7" Y="4.5"/></Wall>"#
    } else {
        ""
    };
    let radius = if sealed_goal { 1.5 } else { 1.0 };
    let lab = format!(
        r#"<Lab Name="pocket" Width="10" Height="6">
  <Beacon X="8.5" Y="3" Height="2"/>
  <Target X="8.5" Y="3" Radius="{radius}"/>
  <Wall Height="1"><Corner X="0" Y="2"/><Corner X="3" Y="2"/><Corner X="3" Y="2.3"/><Corner X="0" Y="2.3"/></Wall>
  <Wall Height="1"><Corner X="3" Y="0"/><Corner X="3.3" Y="0"/><Corner X="3.3" Y="2.3"/><Corner X="3" Y="2.3"/></Wall>
  {ring}
</Lab>"#
    );
    let path = d.join("pocketLab.xml");
    std::fs::write(&path, lab).unwrap();
    let a = load(&path, &LoadOptions::for_simulation()).unwrap();
    let _ = std::fs::remove_dir_all(&d);
    a
}

#[test]
fn without_a_grid_file_the_start_is_a_free_spot_that_reaches_the_goal_or_the_run_is_refused() {
    let radius = f64::from(MICRO_RATO.body_diameter_m) / 2.0;
    let a = lab_with_pocket(false);
    assert!(a.starts.is_empty());
    let w = World::new(a.clone(), Vec::new(), None).unwrap();
    // The scan's first free spot is in the sealed pocket, from which no way leads out.
    let first = w.free_spot(radius).unwrap();
    assert!(first.x < 3.0 * U && first.y < 2.0 * U, "{first:?}");
    let s = start_pose(&w, None, radius).unwrap();
    assert!(
        !(s.x < 3.3 * U && s.y < 2.3 * U),
        "the start is outside the pocket: {s:?}"
    );
    let reached = run_scenario(a, {
        let mut o = ScenarioOptions::new(&MICRO_RATO, Task::ReachBeacon);
        o.seed = 1;
        o.timeout_s = 200.0;
        o
    })
    .unwrap();
    assert!(reached.reached, "{reached:?}");
    // Walls round the goal area: no spot outside it reaches it; the refusal says how to go on.
    let sealed = World::new(lab_with_pocket(true), Vec::new(), None).unwrap();
    let e = start_pose(&sealed, None, radius).unwrap_err();
    assert!(matches!(e, SimError::NoReachableStart { .. }), "{e}");
    let text = e.to_string();
    assert!(
        text.contains("--start") && text.contains("--grid"),
        "{text}"
    );
}

#[test]
fn a_start_inside_any_goal_target_is_reported_and_never_reached() {
    // Two beacons, each over its target; the robot starts inside the second one's.
    let d = temp_dir("inside");
    let lab = r#"<Lab Name="two" Width="14" Height="6">
  <Beacon X="11" Y="3" Height="2"/>
  <Target X="11" Y="3" Radius="1"/>
  <Beacon X="3" Y="3" Height="2"/>
  <Target X="3" Y="3" Radius="1"/>
</Lab>"#;
    std::fs::write(d.join("twoLab.xml"), lab).unwrap();
    std::fs::write(
        d.join("twoGrid.xml"),
        r#"<Grid><Position X="3.2" Y="3" Dir="0"/></Grid>"#,
    )
    .unwrap();
    let a = load(&d.join("twoLab.xml"), &LoadOptions::for_simulation()).unwrap();
    let _ = std::fs::remove_dir_all(&d);
    assert!(
        (Point::new(a.starts[0].x, a.starts[0].y) - Point::new(3.2 * U, 3.0 * U)).norm() < 1e-9
    );
    let mut o = ScenarioOptions::new(&MICRO_RATO, Task::ReachBeacon);
    o.timeout_s = 20.0;
    let r = run_scenario(a, o).unwrap();
    assert!(r.started_in_target, "{r:?}");
    assert!(!r.reached, "{r:?}");
}
