use robot_firmware::{KHEPERA, MICRO_RATO};

use super::*;
use crate::link::Speed;
use crate::scenarios::task::{GoalPoint, Task};

fn parse(args: &[&str]) -> Result<Cli, clap::Error> {
    Cli::try_parse_from(std::iter::once("robot-emulator").chain(args.iter().copied()))
}

#[test]
fn defaults_serve_micro_rato_99_in_real_time() {
    let cli = parse(&[]).expect("no arguments is valid");
    assert!(cli.command.is_none());
    let o = cli.serve.options().expect("valid");
    assert_eq!(o.arena, crate::builtin::MICRO_RATO_99);
    assert_eq!(o.serve.speed, Speed::Factor(1.0));
    assert_eq!(o.sim.baud, 115_200);
}

#[test]
fn bad_values_name_the_flag() {
    let cli = parse(&["--drop-rate", "2"]).expect("parses");
    assert!(cli.serve.options().unwrap_err().contains("drop rate"));
    assert!(parse(&["--speed", "fast"]).is_err());
    assert!(parse(&["--speed", "-1"]).is_err());
    assert!(parse(&["run", "--goal", "1"]).is_err());
    assert!(parse(&["run", "--goal", "1,nan"]).is_err());
    assert!(parse(&["--profile", "roomba"]).is_err());
    let cli = parse(&["--baud", "0"]).expect("parses");
    assert!(cli.serve.options().unwrap_err().contains("--baud"));
    assert!(
        parse(&["--reconnect-after", "1"]).is_err(),
        "needs --disconnect-after"
    );
}

#[test]
fn line_correct_takes_distance_and_line_faults() {
    let cli = parse(&[
        "run",
        "--task",
        "line-correct",
        "--profile",
        "khepera",
        "--arena",
        "builtin:floor-grid",
        "--line-miss",
        "0.3",
        "--distance",
        "12",
    ])
    .expect("valid");
    let Some(Command::Run(r)) = cli.command else {
        panic!("run subcommand")
    };
    let o = r.line_correct_options().expect("valid");
    assert_eq!((o.distance_m, o.noise.line_miss), (12.0, 0.3));
    assert!(r.options().is_err(), "not a go-to scenario");
    let cli = parse(&["run", "--task", "line-correct", "--line-miss", "2"]).expect("parses");
    let Some(Command::Run(r)) = cli.command else {
        panic!("run subcommand")
    };
    let e = r.line_correct_options().unwrap_err();
    assert!(e.contains("--line-miss"), "{e}");
    // Serving the floor-grid arena lays its grid.
    let cli = parse(&["--arena", "builtin:floor-grid", "--profile", "khepera"]).expect("ok");
    let o = cli.serve.options().expect("valid");
    assert_eq!(o.sim.floor_grid_m, Some(0.1));
}

#[test]
fn run_takes_task_goal_and_seed() {
    let cli = parse(&[
        "run",
        "--profile",
        "khepera",
        "--goal",
        "0.4,0.2",
        "--seed",
        "9",
    ])
    .expect("valid");
    let Some(Command::Run(r)) = cli.command else {
        panic!("run subcommand")
    };
    let o = r.options().expect("valid");
    assert_eq!(o.seed, 9);
    assert_eq!(o.task, Task::GoTo(Some(GoalPoint { x_m: 0.4, y_m: 0.2 })));
}

#[test]
fn robots_get_numbered_links_and_their_own_faults_and_seeds() {
    let cli = parse(&[
        "--robots",
        "3",
        "--link",
        "/tmp/robot",
        "--drop-rate",
        "0.01",
        "--drop-rate",
        "2:0.5",
        "--disconnect-after",
        "2:5",
        "--reconnect-after",
        "2:1",
    ])
    .expect("valid");
    let a = &cli.serve;
    assert_eq!(a.robots().expect("valid").map(|r| r.len()), Some(3));
    let l1 = a.link_options(1, 3).expect("valid");
    let l2 = a.link_options(2, 3).expect("valid");
    assert_eq!(
        l1.link.as_deref(),
        Some(std::path::Path::new("/tmp/robot1"))
    );
    assert_eq!(
        l2.link.as_deref(),
        Some(std::path::Path::new("/tmp/robot2"))
    );
    assert_eq!((l1.to_robot.drop_rate, l2.to_robot.drop_rate), (0.01, 0.5));
    assert_eq!(
        (l1.disconnect_after_s, l2.disconnect_after_s),
        (None, Some(5.0))
    );
    assert_eq!(l2.reconnect_after_s, Some(1.0));
    assert_eq!(l1.seed, 1, "robot 1 keeps the run's seed");
    assert_ne!(l2.seed, l1.seed);
    // One robot keeps today's path and faults.
    let one = parse(&["--link", "/tmp/robot", "--drop-rate", "0.2"]).expect("valid");
    assert!(one.serve.robots().expect("valid").is_none());
    let o = one.serve.options().expect("valid");
    assert_eq!(
        o.serve.link.as_deref(),
        Some(std::path::Path::new("/tmp/robot"))
    );
    assert_eq!(o.serve.to_robot.drop_rate, 0.2);
}

#[test]
fn robot_takes_a_profile_and_an_optional_pose_and_profiles_mix() {
    let cli = parse(&[
        "run",
        "--task",
        "reach-beacon",
        "--robot",
        "micro-rato@0.5,0.5,90",
        "--robot",
        "micro-rato",
    ])
    .expect("valid");
    let Some(Command::Run(r)) = cli.command else {
        panic!("run subcommand")
    };
    let c = r.contest_options().expect("valid").expect("a contest");
    assert_eq!(c.robots.len(), 2);
    let s = c.robots[0].start.expect("a pose");
    assert!((s.heading - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    assert!(c.robots[1].start.is_none());
    let mixed = parse(&["--robot", "khepera", "--robot", "micro-rato@1,1"]).expect("valid");
    let specs = mixed.serve.robots().expect("valid").expect("a fleet");
    assert_eq!(specs[0].profile.name, KHEPERA.name);
    assert_eq!(specs[1].profile.name, MICRO_RATO.name);
    assert!(parse(&["--robot", "roomba"]).is_err());
    assert!(parse(&["--robots", "2", "--robot", "khepera"]).is_err());
}
