use super::*;

fn ring(x: f64, y: f64) -> Vec<f64> {
    // A lamp north-east: brighter nearer to it, seen in its direction.
    let (lx, ly) = (3.0, 3.0);
    let bearing = (ly - y).atan2(lx - x);
    let d2 = (lx - x).powi(2) + (ly - y).powi(2);
    (0..24)
        .map(|i| {
            let a = i as f64 * std::f64::consts::TAU / 24.0;
            let off = wrap(bearing - a);
            (2.0 / d2) * (-(off * off) / 0.1).exp()
        })
        .collect()
}

/// With exact odometry the model grows cells along the way and joins consecutive winners;
/// malformed samples are refused with the reason.
#[test]
fn a_walk_builds_a_connected_chain_and_bad_samples_are_refused() {
    let mut m = QtModel::new(Params::default(), Pose::default()).expect("valid");
    let touch = vec![false; 24];
    for i in 0..60 {
        let x = 0.05 * f64::from(i);
        let light = ring(x, 0.0);
        let s = Sample {
            light: &light,
            touch: &touch,
            odometry: Pose {
                x,
                y: 0.0,
                heading: 0.0,
            },
        };
        m.observe(&s).expect("valid sample");
    }
    let net = m.network();
    assert!(net.len() >= 5, "{} cells", net.len());
    assert!(
        net.cells().all(|(_, c)| !c.edges.is_empty()),
        "no isolated cell"
    );
    assert_eq!(m.stats().samples, 60);
    let light = ring(0.0, 0.0);
    let short = Sample {
        light: &light[..10],
        touch: &touch,
        odometry: Pose::default(),
    };
    assert!(m.observe(&short).is_err());
    let nan = Sample {
        light: &light,
        touch: &touch,
        odometry: Pose {
            x: f64::NAN,
            y: 0.0,
            heading: 0.0,
        },
    };
    assert!(m.observe(&nan).is_err());
    assert_eq!(m.stats().samples, 60, "refused samples change nothing");
}

/// Every named parameter can be set by name and is range-checked.
#[test]
fn parameters_are_settable_by_name_and_checked() {
    let mut p = Params::default();
    p.set("eps_o", "0.05").expect("in range");
    assert_eq!(p.eps_o, 0.05);
    assert!(p.set("a_red", "0").is_err());
    assert!(p.set("eps_delta", "1").is_err());
    assert!(p.set("nope", "1").is_err());
    // A refused value leaves the parameters as they were (it used to stay, invalid).
    assert_eq!(p.a_red, Params::default().a_red);
    p.validate().expect("still valid");
    assert!(p.set("or_method", "axis").is_ok());
    assert!(p.set("pos_distance", "situation").is_ok());
    assert_eq!(p.pos_distance, PosDistance::Situation);
    assert!(p.set("pos_distance", "both").is_err());
    assert!(p.set("or_pos_tolerance", "-1").is_err());
    assert!(p.set("or_pos_tolerance", "NaN").is_err());
    assert!(p.set("or_pos_tolerance", "inf").is_ok());
    assert!(p.set("pos_sigma", "0").is_err());
    assert!(p.assign("pos_sigma").is_err());
    p.assign("pos_sigma=0.05").expect("an assignment");
    assert_eq!(p.pos_sigma, 0.05);
    assert!(p.set("pos_sigma", "-0.1").is_err());
    assert!(p.set("pos_sigma", "inf").is_err());
    p.set("pos_sigma", "0.1").expect("in range");
    assert_eq!(p.pos_sigma, 0.1);
}

/// §4.2.4's p_est leans on the cells whose readings match best: three cells 0.3 m apart in
/// a row, joined in a chain, the pose at the middle one (so it wins: the search weighs
/// the position) and the readings those of the cell at 0.6 m, a lamp 0.8 m off the row. With the default
/// `pos_sigma` the estimate is at that cell; with weights as wide as d_acc (the earlier
/// default) it is pulled back towards the middle of the chain.
#[test]
fn the_position_estimate_follows_the_best_matching_cell() {
    // A lamp just beside the row, so the three places' rings differ clearly.
    let ring = |x: f64, y: f64| -> Vec<f64> {
        let bearing = (0.8 - y).atan2(0.3 - x);
        (0..24)
            .map(|i| {
                let off = wrap(bearing - i as f64 * std::f64::consts::TAU / 24.0);
                (-(off * off) / 0.1).exp()
            })
            .collect()
    };
    let estimate = |pos_sigma: f64| {
        let p = Params {
            pos_sigma,
            ..Params::default()
        };
        let mut m = QtModel::new(p.clone(), Pose::default()).expect("valid");
        let touch = vec![false; 24];
        let mut ids = Vec::new();
        for x in [0.0, 0.3, 0.6] {
            let mut s = Vec::new();
            let at = Pose {
                x,
                y: 0.0,
                heading: 0.0,
            };
            situation(&p, &ring(x, 0.0), &touch, at, &mut s);
            ids.push(m.net.insert(s, 0.0).expect("room"));
        }
        m.net.set_edge(ids[0], ids[1], 1.0);
        m.net.set_edge(ids[1], ids[2], 1.0);
        m.relocate(Pose {
            x: 0.3,
            y: 0.0,
            heading: 0.0,
        });
        let light = ring(0.6, 0.0);
        let sample = Sample {
            light: &light,
            touch: &touch,
            odometry: Pose::default(),
        };
        m.position_estimate(&sample).expect("an estimate").0
    };
    let sharp = estimate(Params::default().pos_sigma);
    let wide = estimate(0.8);
    assert!(sharp > 0.55, "default pos_sigma: {sharp}");
    assert!(wide < 0.5, "pos_sigma 0.8: {wide}");
}

/// `last_estimate` is the p_est the position correlation used: with eps_pos 1 the pose
/// jumps onto it; with both correlations off none is made.
#[test]
fn the_last_estimate_is_the_one_the_correlation_used() {
    let full = Params {
        eps_pos: 1.0,
        ..Params::default()
    };
    let mut m = QtModel::new(full, Pose::default()).expect("valid");
    let mut made = 0;
    out_and_back(&mut m, |m| {
        if let Some((x, y)) = m.last_estimate() {
            made += 1;
            // x + 1 * (est - x): equal but for the last bit.
            let off = (m.pose().x - x).hypot(m.pose().y - y);
            assert!(off < 1e-12, "pose {:?}, estimate {:?}", m.pose(), (x, y));
        }
    });
    assert!(made > 100, "{made} estimates");
    let off = Params {
        eps_pos: 0.0,
        eps_or: 0.0,
        ..Params::default()
    };
    let mut m = QtModel::new(off, Pose::default()).expect("valid");
    out_and_back(&mut m, |m| assert_eq!(m.last_estimate(), None));
}

/// 200 samples out and back along a line (exact odometry), so the second half meets the
/// first's cells; `after` sees the model after each.
fn out_and_back(m: &mut QtModel, mut after: impl FnMut(&QtModel)) {
    let touch = vec![false; 24];
    for i in 0..200 {
        let x = 0.05 * f64::from(if i < 100 { i } else { 200 - i });
        let light = ring(x, 0.0);
        let odometry = Pose {
            x,
            y: 0.0,
            heading: 0.0,
        };
        let s = Sample {
            light: &light,
            touch: &touch,
            odometry,
        };
        m.observe(&s).expect("valid sample");
        after(m);
    }
}

/// `Stats::since` is what a stretch did: a second walk's counts are the whole run's less
/// the first walk's, field by field.
#[test]
fn the_counts_since_a_copy_are_the_stretch_s_own() {
    let mut m = QtModel::new(Params::default(), Pose::default()).expect("valid");
    out_and_back(&mut m, |_| {});
    let first = m.stats().clone();
    out_and_back(&mut m, |_| {});
    let d = m.stats().since(&first);
    assert_eq!(d.samples, 200);
    assert_eq!(d.adaptations, m.stats().adaptations - first.adaptations);
    assert_eq!(d.or_reached(), m.stats().or_reached() - first.or_reached());
    assert_eq!(
        d.edges_refreshed,
        m.stats().edges_refreshed - first.edges_refreshed
    );
    assert!(d.edges_refreshed > 0, "{d:?}");
    assert_eq!(m.stats().since(m.stats()), Stats::default());
}

/// A static map (§5.3): a second walk out and back changes no cell, edge, update count
/// or adaptation rate, while the winner still follows the robot and the correlations
/// still run; the same walk on a learning map moves cells and creates or refreshes edges.
#[test]
fn a_static_map_changes_nothing_but_still_localises() {
    let snapshot = |m: &QtModel| {
        let net = m.network();
        net.cells()
            .map(|(id, c)| (id, c.s.clone(), c.updates, c.d_total, c.edges.clone()))
            .collect::<Vec<_>>()
    };
    let mut m = QtModel::new(Params::default(), Pose::default()).expect("valid");
    out_and_back(&mut m, |_| {});
    let mut learning = m.clone();
    let s = learning.stats().clone();
    out_and_back(&mut learning, |_| {});
    let l = learning.stats();
    assert!(l.edges_created + l.edges_refreshed > s.edges_created + s.edges_refreshed);
    assert!(l.cell_moves > s.cell_moves, "{l:?}");
    m.set_static(true);
    assert!(m.is_static());
    let (before, stats, rates) = (snapshot(&m), m.stats().clone(), m.rates());
    let mut winners = std::collections::HashSet::new();
    out_and_back(&mut m, |m| {
        winners.extend(m.winner());
    });
    assert_eq!(snapshot(&m), before, "the map changed");
    assert_eq!(m.rates(), rates);
    let after = m.stats();
    let learned = |s: &Stats| {
        [
            s.adaptations,
            s.cell_moves,
            s.edges_created,
            s.edges_refreshed,
            s.edges_worn,
            s.spontaneous + s.statistical + s.removed + s.misses,
        ]
    };
    assert_eq!(learned(after), learned(&stats));
    assert!(
        winners.len() > 3,
        "the winner follows the walk: {winners:?}"
    );
    assert!(after.pos_corrections > stats.pos_corrections);
    assert_eq!(after.or_reached(), after.samples);
}

/// §4.2.4's "correct to within a certain tolerance": at a zero tolerance the heading is
/// never corrected (the map's estimate never agrees exactly), the position still is.
#[test]
fn the_orientation_correlation_waits_for_a_trusted_position() {
    let walk = |tolerance: f64| {
        let p = Params {
            or_pos_tolerance: tolerance,
            ..Params::default()
        };
        let mut m = QtModel::new(p, Pose::default()).expect("valid");
        out_and_back(&mut m, |_| {});
        m.stats().clone()
    };
    let gated = walk(0.0);
    assert!(gated.pos_corrections > 0);
    assert_eq!(gated.or_corrections, 0);
    assert!(walk(f64::INFINITY).or_corrections > 0);
}

/// Every sample observed while the orientation correlation is on counts in exactly one
/// of its outcomes, and each outcome is reachable: a flat ring, a ring turned beyond the
/// search, another place's ring, the place's own ring, and an untrusted position.
#[test]
fn the_orientation_correlation_counts_one_outcome_per_sample() {
    let touch = vec![false; 24];
    let walk = |m: &mut QtModel| {
        out_and_back(m, |m| {
            assert_eq!(m.stats().or_reached(), m.stats().samples, "{:?}", m.stats());
        });
    };
    let mut m = QtModel::new(Params::default(), Pose::default()).expect("valid");
    walk(&mut m);
    let s = m.stats().clone();
    assert_eq!(s.or_untrusted, 0, "no gate at the default tolerance");
    assert!(s.or_no_cell >= 1, "the first sample meets an empty network");
    assert!(s.or_corrections > 0, "{s:?}");
    // Probes where the walk ended (x = 0.05): the odometry stands still.
    let here = ring(0.05, 0.0);
    let mut turned = Vec::new();
    crate::situation::rotate_to_world(&here, 1.0, &mut turned);
    let mut opposite = Vec::new();
    crate::situation::rotate_to_world(&here, std::f64::consts::PI, &mut opposite);
    let other: Vec<f64> = here.iter().zip(&opposite).map(|(a, b)| a + b).collect();
    let flat = vec![0.5; 24];
    type Count = fn(&Stats) -> u64;
    let probes: [(&[f64], Count); 4] = [
        (&flat, |s| s.or_no_pattern),
        (&turned, |s| s.or_no_turn),
        (&other, |s| s.or_residual),
        (&here, |s| s.or_corrections),
    ];
    let odometry = Pose {
        x: 0.05,
        y: 0.0,
        heading: 0.0,
    };
    for (light, count) in probes {
        let before = m.stats().clone();
        let s = Sample {
            light,
            touch: &touch,
            odometry,
        };
        m.observe(&s).expect("valid sample");
        let after = m.stats();
        assert_eq!(count(after), count(&before) + 1, "{before:?} -> {after:?}");
        assert_eq!(after.or_reached(), before.or_reached() + 1);
    }
    // Off: nothing reaches the correlation.
    m.set_params(Params {
        eps_or: 0.0,
        ..Params::default()
    })
    .expect("valid");
    let before = m.stats().or_reached();
    let s = Sample {
        light: &here,
        touch: &touch,
        odometry,
    };
    m.observe(&s).expect("valid sample");
    assert_eq!(m.stats().or_reached(), before);
    // A zero tolerance trusts no estimate: every sample is untrusted once the network has
    // a cell (the first l + 1 samples meet an empty one: the delay l).
    let p = Params {
        or_pos_tolerance: 0.0,
        ..Params::default()
    };
    let empty = p.l as u64 + 1;
    let mut m = QtModel::new(p, Pose::default()).expect("valid");
    walk(&mut m);
    let s = m.stats();
    assert_eq!(
        (s.or_no_cell, s.or_untrusted),
        (empty, 200 - empty),
        "{s:?}"
    );
    // The axis method: a flat ring has no axis.
    let p = Params {
        or_method: OrMethod::Axis,
        ..Params::default()
    };
    let mut m = QtModel::new(p, Pose::default()).expect("valid");
    walk(&mut m);
    let before = m.stats().or_no_pattern;
    let s = Sample {
        light: &flat,
        touch: &touch,
        odometry,
    };
    m.observe(&s).expect("valid sample");
    assert_eq!(m.stats().or_no_pattern, before + 1);
    assert_eq!(m.stats().or_reached(), m.stats().samples);
}
