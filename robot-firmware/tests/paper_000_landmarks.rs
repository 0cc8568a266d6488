//! Seed 000 (Löffler et al. 2001) §6 reproduced on the host: three-landmark resection, its
//! singular circle and its error table (Eq 45, Fig 39), light-source triangulation and the
//! K213 landmark initialisation.
//!
//! Eq 45 is a linear error propagation: `F = sqrt((|dx/dd1| + |dx/dd2|)^2 + (|dy/dd1| +
//! |dy/dd2|)^2) F_delta` with `F_delta = 2 px * 18 deg / 64 px = 0.5625 deg`. We evaluate it
//! as the paper defines it (derivatives by central differences of our resection, in f64) and,
//! for comparison only, also print the worst position error over the four corner
//! perturbations (±F_delta, ±F_delta) of the measured angles. Run with `--nocapture`.
#![allow(clippy::unwrap_used, clippy::panic)]

use robot_firmware::landmarks::{
    triangulate, BearingFix, Camera, LandmarkError, Triple, F_DELTA_RAD,
};
use robot_firmware::odometry::{wrap_angle, Point, Pose};

/// The paper's example (§6.2, Fig 39), millimetres.
const L: [(f32, f32); 3] = [(0.0, 1000.0), (200.0, 1100.0), (500.0, 1000.0)];

fn mm(p: (f32, f32)) -> Point {
    Point::new(p.0 / 1000.0, p.1 / 1000.0)
}

fn triple() -> Triple {
    Triple::new(mm(L[0]), mm(L[1]), mm(L[2]))
}

/// Exact angles (d1, d2) a robot at `r` sees between L1-L2 and L2-L3.
fn angles(r: Point) -> (f32, f32) {
    let b = L.map(|l| f64::from(r.bearing_to(mm(l))));
    let w = |a: f64| f64::from(wrap_angle(a as f32));
    (w(b[0] - b[1]) as f32, w(b[1] - b[2]) as f32)
}

#[test]
fn the_example_landmarks_lie_on_a_circle_centred_at_250_750_with_radius_354() {
    let (c, r) = triple().circle().unwrap();
    println!(
        "circle: centre ({:.1}, {:.1}) mm, r = {:.1} mm (paper (250, 750), 354)",
        c.x * 1e3,
        c.y * 1e3,
        r * 1e3
    );
    assert!((c.x - 0.25).abs() < 1e-6 && (c.y - 0.75).abs() < 1e-6);
    assert!((r * 1e3 - 354.0).abs() < 0.5, "{r}");
}

#[test]
fn eq_45_errors_match_the_papers_table() {
    // (robot position mm, paper's error mm)
    let table = [
        ((250.0, 800.0), 8.6f64),
        ((250.0, 600.0), 54.5),
        ((250.0, 400.0), 8169.0),
        ((250.0, 200.0), 317.0),
        ((250.0, 0.0), 292.0),
        ((-300.0, 500.0), 139.0),
        ((800.0, 500.0), 163.0),
    ];
    assert!((F_DELTA_RAD.to_degrees() - 0.5625).abs() < 1e-5);
    let t = triple();
    println!("robot (mm)     | paper | Eq 45 (ours) | worst of ±F_delta corners");
    for ((x, y), paper) in table {
        let r = mm((x, y));
        let (d1, d2) = angles(r);
        let f = f64::from(t.error(d1, d2, F_DELTA_RAD).unwrap()) * 1e3;
        let worst = [(1.0f32, 1.0f32), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)]
            .iter()
            .filter_map(|(s1, s2)| t.resect(d1 + s1 * F_DELTA_RAD, d2 + s2 * F_DELTA_RAD).ok())
            .map(|p| f64::from(p.distance_to(r)) * 1e3)
            .fold(0.0, f64::max);
        println!("({x:>5}, {y:>5}) | {paper:>5} | {f:>12.1} | {worst:>8.1}");
        // The paper prints three significant figures: we allow 1 % (0.1 mm for 8.6).
        let tol = (0.01 * paper).max(0.1);
        assert!((f - paper).abs() <= tol, "({x}, {y}): {f} vs {paper}");
    }
}

#[test]
fn resection_recovers_exact_positions_and_headings_from_exact_angles() {
    let t = triple();
    let (c, r) = t.circle().unwrap();
    let mut checked = 0;
    for ix in -6..=16 {
        for iy in -4..=9 {
            let p = Point::new(ix as f32 * 0.05, iy as f32 * 0.05);
            // Away from the singular circle (Fig 38) and below the landmarks (Fig 34).
            if (p.distance_to(c) - r).abs() < 0.02 || p.y > 0.5 {
                continue;
            }
            for heading in [0.3f32, 1.5, 2.8] {
                let bearings = L.map(|l| wrap_angle(p.bearing_to(mm(l)) - heading));
                let Ok(pose) = t.resect_pose(bearings) else {
                    // Outer landmarks 180 deg apart or more: not a valid view (Fig 34).
                    continue;
                };
                // Exact up to the f32 rounding of the input angles: a few 1e-7 rad, times the
                // sensitivity Eq 45 measures (large near the circle).
                let (d1, d2) = angles(p);
                let tol = 2e-6 + t.error(d1, d2, 5e-7).unwrap();
                assert!(
                    pose.point().distance_to(p) < tol,
                    "{p:?} -> {pose:?} ({tol})"
                );
                assert!(
                    wrap_angle(pose.heading - heading).abs() < 1e-4,
                    "{p:?} {pose:?}"
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 500, "{checked}");
}

#[test]
fn the_printed_t3_is_wrong_and_the_digests_fix_gives_the_angle_at_l2() {
    // gamma must be the angle L1-L2-L3 on the robot's side: 135 deg for the example.
    let slope = |a: (f32, f32), b: (f32, f32)| {
        (f64::from(b.1) - f64::from(a.1)) / (f64::from(b.0) - f64::from(a.0))
    };
    let t1 = slope(L[0], L[1]).atan();
    let printed = (t1 - (core::f64::consts::PI - slope(L[1], L[2]).atan())).abs();
    let fixed = (t1 - (core::f64::consts::PI + slope(L[1], L[2]).atan())).abs();
    assert!(
        (fixed.to_degrees() - 135.0).abs() < 1e-9,
        "{}",
        fixed.to_degrees()
    );
    assert!(
        (printed.to_degrees() - 135.0).abs() > 30.0,
        "{}",
        printed.to_degrees()
    );
    // And our general form resects the example as exactly as the fixed printed one would.
    let r = mm((250.0, 200.0));
    let (d1, d2) = angles(r);
    assert!(triple().resect(d1, d2).unwrap().distance_to(r) < 1e-5);
}

#[test]
fn a_robot_on_the_circle_through_the_landmarks_has_no_fix() {
    let t = triple();
    let (c, r) = t.circle().unwrap();
    for a in [-100.0f32, -90.0, -60.0, -120.0] {
        let p = Point::new(
            c.x + r * a.to_radians().cos(),
            c.y + r * a.to_radians().sin(),
        );
        let (d1, d2) = angles(p);
        assert_eq!(t.resect(d1, d2), Err(LandmarkError::Singular), "{p:?}");
    }
    // 5 cm off the circle the fix exists but is poor; at the circle's centre it is good.
    let near = Point::new(c.x, c.y - r - 0.05);
    let (d1, d2) = angles(near);
    assert!(t.error(d1, d2, F_DELTA_RAD).unwrap() > 0.5);
    let (d1, d2) = angles(c);
    assert!(t.error(d1, d2, F_DELTA_RAD).unwrap() < 0.015);
    // Invalid angles are refused, not computed.
    assert_eq!(t.resect(0.0, 0.5), Err(LandmarkError::BadAngles));
    assert_eq!(t.resect(2.0, 1.5), Err(LandmarkError::BadAngles));
    assert_eq!(t.resect(f32::NAN, 0.5), Err(LandmarkError::BadAngles));
    let same = Triple::new(mm(L[0]), mm(L[0]), mm(L[2]));
    assert_eq!(same.resect(0.3, 0.3), Err(LandmarkError::Degenerate));
}

#[test]
fn triangulation_recovers_a_light_source_from_two_approaches() {
    // §6.1: the robot reaches the optimal distance twice, about 90 deg apart, and stores
    // (x, y, heading + SOM angle) each time.
    let light = Point::new(0.42, 0.31);
    let stop = |x: f32, y: f32, heading: f32| {
        let p = Point::new(x, y);
        let som_angle = wrap_angle(p.bearing_to(light) - heading);
        BearingFix {
            position: p,
            bearing: heading + som_angle,
        }
    };
    let got = triangulate(stop(0.38, 0.30, 0.1), stop(0.43, 0.35, -1.2)).unwrap();
    assert!(got.distance_to(light) < 1e-6, "{got:?}");
    // A 1.52 deg SOM error (§5.3's mean) at 4 cm moves the estimate by about a millimetre.
    let mut second = stop(0.43, 0.35, -1.2);
    second.bearing += 1.52f32.to_radians();
    let off = triangulate(stop(0.38, 0.30, 0.1), second)
        .unwrap()
        .distance_to(light);
    assert!(off > 1e-4 && off < 3e-3, "{off}");
}

#[test]
fn the_camera_maps_three_landmarks_and_resection_then_finds_the_robot() {
    // Initialisation (§6.2): from a known pose, each landmark's image angle (a pixel, as the
    // camera quantises it) and SOM distance give its position (Eqs 29-31).
    let cam = Camera::K213;
    let robot = Pose::new(0.25, 0.45, 1.4);
    let mut mapped = [Point::default(); 3];
    for (k, l) in L.iter().enumerate() {
        let l = mm(*l);
        // The landmark as the camera, 5 mm left of the centre, sees it.
        let (s, c) = (robot.heading.sin(), robot.heading.cos());
        let cam_pos = Point::new(robot.x - cam.offset_m * s, robot.y + cam.offset_m * c);
        let l_v = cam_pos.distance_to(l);
        let a_prime = wrap_angle(cam_pos.bearing_to(l) - robot.heading);
        // Inverse of `pixel_angle`, rounded to the nearest 1/4 px (a mid-point of two edges).
        let px = (31.5 - a_prime * 64.0 / cam.fov_rad) * 4.0;
        let a_img = cam.pixel_angle(px.round() / 4.0);
        let alpha_k = cam.bearing(l_v, a_img);
        mapped[k] = robot_firmware::landmarks::landmark_position(robot, l_v, alpha_k);
        // Eq 30-31 use the camera distance: within 2 mm plus the quarter pixel.
        let err = mapped[k].distance_to(l);
        assert!(err < 0.004, "landmark {k}: {err}");
    }
    // Operation: resection against the mapped landmarks from a new pose.
    let t = Triple::new(mapped[0], mapped[1], mapped[2]);
    let truth = Pose::new(0.2, 0.3, 1.2);
    let bearings = L.map(|l| wrap_angle(truth.point().bearing_to(mm(l)) - truth.heading));
    let fix = t.resect_pose(bearings).unwrap();
    println!("fix from mapped landmarks: {fix:?} (truth {truth:?})");
    assert!(fix.point().distance_to(truth.point()) < 0.02, "{fix:?}");
}
