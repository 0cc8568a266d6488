//! Arbitration tests: each rule of seed 000 §4 at the arbiter's level, and a go-to run.

use super::*;
use crate::odometry::{wrap_angle, Pose};
use core::f32::consts::{FRAC_PI_2, PI};

const DARK: [u16; 8] = [500; 8];
const CLEAR: [u16; 8] = [0; 8];

fn arbiter(mode: Mode) -> Arbiter {
    let mut a = Arbiter::new(ArbiterParams::default(), 42);
    a.set_mode(mode);
    a
}

fn at(ir: [u16; 8], pose: Pose) -> Inputs {
    Inputs::fresh(ir, DARK, pose)
}

fn s0(v: u16) -> [u16; 8] {
    [v, 0, 0, 0, 0, 0, 0, 0]
}

/// Differential-drive kinematics for one 80 ms Khepera cycle (d = 52 mm).
fn drive(pose: Pose, cmd: MotorCommand) -> Pose {
    let (l, r) = cmd.to_mps();
    let dt = 0.08;
    let w = (r - l) / 0.052;
    let mid = pose.heading + w * dt / 2.0;
    let v = (l + r) / 2.0;
    Pose::new(
        pose.x + v * dt * libm::cosf(mid),
        pose.y + v * dt * libm::sinf(mid),
        pose.heading + w * dt,
    )
}

#[test]
fn idle_stops_the_motors() {
    let mut a = Arbiter::new(ArbiterParams::default(), 1);
    assert_eq!(a.step(&at(CLEAR, Pose::default())), MotorCommand::STOP);
}

#[test]
fn wander_gives_base_propulsion_and_avoids_obstacles() {
    let mut a = arbiter(Mode::Wander);
    assert_eq!(a.step(&at(CLEAR, Pose::default())), MotorCommand::new(6, 6));
    assert_eq!(a.state().active, BehaviourSet(0));
    let cmd = a.step(&at([0, 900, 900, 0, 0, 0, 0, 0], Pose::default()));
    assert!(
        cmd.right < cmd.left,
        "obstacle on the left: turn right, {cmd:?}"
    );
    assert!(a.state().active.contains(BehaviourSet::AVOID));
}

#[test]
fn edge_following_output_is_added_to_avoidance() {
    let mut a = arbiter(Mode::EdgeFollow(Side::Left));
    assert_eq!(
        a.step(&at(s0(300), Pose::default())),
        MotorCommand::new(6, 6)
    );
    assert_eq!(
        a.step(&at(s0(292), Pose::default())),
        MotorCommand::new(5, 6)
    );
    let st = *a.state();
    assert_eq!(
        (st.avoid, st.edge),
        (MotorCommand::new(6, 6), MotorCommand::new(-1, 0))
    );
    // An obstacle on the right at the same time: avoidance slows the left wheel, edge adds -1.
    let ir = [292, 0, 0, 900, 900, 0, 0, 0];
    let cmd = a.step(&at(ir, Pose::default()));
    let st = *a.state();
    assert_eq!(cmd, st.avoid.plus(st.edge));
    assert!(cmd.left < 5 && st.active.contains(BehaviourSet::AVOID));
    assert!(st.active.contains(BehaviourSet::EDGE));
}

#[test]
fn turning_suppresses_all_other_behaviours() {
    let mut a = arbiter(Mode::EdgeFollow(Side::Left));
    a.step(&at(s0(300), Pose::default()));
    let dead_end = [350, 200, 600, 650, 100, 400, 0, 0];
    let cmd = a.step(&at(dead_end, Pose::default()));
    let st = *a.state();
    assert!(st.dead_end);
    assert_eq!(st.turn_reason, Some(TurnReason::DeadEnd));
    assert_eq!(cmd.left, -cmd.right, "on the spot");
    assert_eq!(st.active, BehaviourSet(BehaviourSet::TURN));
    assert_eq!(
        a.edge.memory(),
        Some(-300),
        "edge following was not stepped"
    );
    // Turn until done, then edge following restarts with a reset.
    let mut pose = Pose::default();
    let mut cmd = cmd;
    for _ in 0..100 {
        pose = drive(pose, cmd);
        cmd = a.step(&at(s0(120), pose));
        if a.state().turn_reason.is_none() {
            break;
        }
    }
    assert!((libm::fabsf(pose.heading) - PI).abs() < 0.1, "{pose:?}");
    assert_eq!(cmd, MotorCommand::new(6, 6));
    assert_eq!(a.edge.memory(), Some(-120));
}

#[test]
fn stale_outputs_are_reused_for_a_few_cycles_then_dropped() {
    let mut a = arbiter(Mode::EdgeFollow(Side::Left));
    a.step(&at(s0(300), Pose::default()));
    assert_eq!(
        a.step(&at(s0(292), Pose::default())),
        MotorCommand::new(5, 6)
    );
    let stale = Inputs {
        ir_fresh: false,
        ..at([1023; 8], Pose::default())
    };
    for _ in 0..3 {
        assert_eq!(a.step(&stale), MotorCommand::new(5, 6));
        let st = a.state().stale;
        assert!(st.contains(BehaviourSet::AVOID) && st.contains(BehaviourSet::EDGE));
    }
    assert_eq!(a.step(&stale), MotorCommand::STOP, "too old: no propulsion");
    assert_eq!(
        a.step(&at(s0(292), Pose::default())),
        MotorCommand::new(5, 6)
    );
}

#[test]
fn go_to_turns_first_then_reaches_the_point_with_halved_propulsion_near_it() {
    let target = Point::new(0.5, 0.3);
    let mut a = arbiter(Mode::GoTo(target));
    let mut pose = Pose::new(0.0, 0.0, PI);
    let first = a.step(&at(CLEAR, pose));
    assert_eq!(first.left, -first.right, "initial turn on the spot");
    let mut cmd = first;
    let mut cycles = 0;
    while a.state().drift_phase != DriftPhase::Reached {
        pose = drive(pose, cmd);
        cmd = a.step(&at(CLEAR, pose));
        let near = pose.point().distance_to(target) < 0.15;
        if near && a.state().turn == MotorCommand::STOP && cmd.left != -cmd.right {
            assert!(
                cmd.left + cmd.right <= 6,
                "half propulsion near the target: {cmd:?}"
            );
        }
        cycles += 1;
        assert!(cycles < 1000, "never arrived: {pose:?}");
    }
    assert!(pose.point().distance_to(target) < 0.05);
    assert_eq!(cmd, MotorCommand::STOP);
    assert_eq!(a.step(&at(CLEAR, pose)), MotorCommand::STOP);
}

#[test]
fn a_paused_drift_follows_an_edge_instead() {
    let mut a = arbiter(Mode::GoTo(Point::new(0.0, 1.0)));
    let path = [
        (0.0, 0.0),
        (0.2, -0.1),
        (0.02, 0.0),
        (-0.2, -0.1),
        (0.0, 0.01),
    ];
    for (x, y) in path {
        a.step(&at(s0(300), Pose::new(x, y, FRAC_PI_2)));
    }
    let st = *a.state();
    assert!(
        matches!(st.drift_phase, DriftPhase::Paused { .. }),
        "{st:?}"
    );
    assert!(st.active.contains(BehaviourSet::EDGE) && !st.active.contains(BehaviourSet::DRIFT));
    let cmd = a.step(&at(s0(290), Pose::new(0.0, 0.01, FRAC_PI_2)));
    assert_eq!(
        cmd,
        MotorCommand::new(5, 6),
        "edge following's -1 on base propulsion"
    );
}

#[test]
fn drive_to_light_steers_to_the_source_and_stops_at_the_optimal_distance() {
    let mut a = arbiter(Mode::DriveToLight);
    let mut light = Inputs::fresh(
        CLEAR,
        [200, 200, 350, 480, 500, 500, 500, 500],
        Pose::default(),
    );
    let cmd = a.step(&light);
    assert_eq!(
        cmd,
        MotorCommand::new(6, 11),
        "turns left towards the light"
    );
    assert!(a.state().active.contains(BehaviourSet::LIGHT));
    light.light = [150; 8];
    assert_eq!(a.step(&light), MotorCommand::STOP);
    assert_eq!(a.state().light_phase, LightPhase::Arrived);
    a.release_light();
    assert_eq!(
        a.step(&light),
        MotorCommand::new(6, 6),
        "leaving: plain propulsion"
    );
}

#[test]
fn the_same_seed_gives_the_same_run_and_thresholds_stay_in_range() {
    let run = |seed: u32| {
        let mut a = Arbiter::new(ArbiterParams::default(), seed);
        a.set_mode(Mode::Wander);
        let mut out = [MotorCommand::STOP; 40];
        for (i, o) in out.iter_mut().enumerate() {
            let v = if i % 2 == 0 { 480 } else { 0 };
            *o = a.step(&at([0, v, v, v, v, 0, 0, 0], Pose::default()));
            let [l, r] = a.state().avoid_thresholds;
            assert!((450..=500).contains(&l) && (450..=500).contains(&r));
        }
        out
    };
    assert_eq!(run(7), run(7));
    assert_ne!(run(7), run(8));
}

#[test]
fn a_stale_pose_reuses_the_last_drift_correction() {
    let mut a = arbiter(Mode::GoTo(Point::new(2.0, 0.0)));
    a.step(&at(CLEAR, Pose::new(0.0, 0.0, 0.0)));
    let cmd = a.step(&at(
        CLEAR,
        Pose::new(0.0, 0.0, wrap_angle(-40f32.to_radians())),
    ));
    assert_eq!(cmd, MotorCommand::new(0, 6));
    let stale = Inputs {
        pose_fresh: false,
        ..at(CLEAR, Pose::new(0.0, 0.0, 0.0))
    };
    assert_eq!(a.step(&stale), MotorCommand::new(0, 6));
    assert!(a.state().stale.contains(BehaviourSet::DRIFT));
}

#[test]
fn go_to_pressed_against_a_wall_across_its_way_pauses_to_follow_the_edge() {
    // A flat wall ahead (no dead-end pattern): avoidance and drift cancel, the robot stays put
    // and never leaves its nearest point. The circle criterion's 180° turns must count as
    // cyclic behaviour: first the drift is halved, then navigation pauses (seed 000 §4.4).
    let mut a = arbiter(Mode::GoTo(Point::new(1.0, 0.0)));
    let wall = [0, 200, 650, 650, 200, 0, 0, 0];
    let mut pose = Pose::new(0.0, 0.0, 0.0);
    let mut paused_at = None;
    for cycle in 0..2000 {
        // Only the heading changes: the wall stops the robot; facing away it sees nothing.
        let facing = libm::cosf(pose.heading) > 0.7;
        let cmd = a.step(&at(if facing { wall } else { CLEAR }, pose));
        let turned = drive(pose, cmd);
        pose = Pose::new(0.0, 0.0, turned.heading);
        if matches!(a.state().drift_phase, DriftPhase::Paused { .. }) {
            paused_at = Some(cycle);
            break;
        }
    }
    let cycle = paused_at.expect("navigation never paused: the robot sits at the wall");
    assert!(a.drift().failures() >= 1);
    assert_eq!(a.drift().factor(), 0.5, "halved on the first 180° turn");
    // Two circle periods (200 cycles each) plus the turns.
    assert!(cycle < 700, "{cycle}");
}

#[test]
fn go_to_standing_still_where_avoidance_and_drift_cancel_is_cyclic_within_seconds() {
    // The target 40° to the left, an obstacle on the left front: drift slows the left wheel,
    // avoidance the right one, and for some reading they cancel and the robot stands still
    // (what the box benchmark's failed runs did for 15-39 % of their time). Four seconds of
    // commanded standstill are one sign of cyclic behaviour (seed 000 §4.4): the drift is
    // halved, which lets avoidance turn the robot away. Before, only the circle criterion
    // noticed, after 200 cycles (16 s).
    // Aligned first (drift turns on the spot before it drives), then turned away by 40°.
    let facing = Pose::new(0.0, 0.0, FRAC_PI_2);
    let pose = Pose::new(0.0, 0.0, FRAC_PI_2 - 0.7);
    let target = Point::new(0.0, 1.0);
    let still = |cmd: MotorCommand| cmd.left.abs() <= 1 && cmd.right.abs() <= 1;
    let reading = (0..1023u16).step_by(5).find(|&v| {
        let mut a = arbiter(Mode::GoTo(target));
        a.step(&at(CLEAR, facing));
        still(a.step(&at([0, v, v, 0, 0, 0, 0, 0], pose)))
    });
    let v = reading.expect("some reading cancels the drift");
    let mut a = arbiter(Mode::GoTo(target));
    a.step(&at(CLEAR, facing));
    let mut halved_at = None;
    for cycle in 0..190u16 {
        a.step(&at([0, v, v, 0, 0, 0, 0, 0], pose));
        if a.drift().factor() < 1.0 {
            halved_at = Some(cycle);
            break;
        }
    }
    let cycle = halved_at.expect("standing still was never taken as cyclic behaviour");
    assert!(cycle <= 60, "{cycle}");
    assert_eq!(a.drift().phase(), DriftPhase::Driving);
}
