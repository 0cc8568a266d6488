//! Probe: one ALICE QT run, checkpoints printed (development aid).
use emulator::alice::scenario::{run, RunOptions};
fn main() {
    let mut args = std::env::args().skip(1);
    let seed: u64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(1);
    let samples: u64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(6000);
    let mut o = RunOptions::new(seed, samples);
    o.checkpoint = std::env::var("CP")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(500);
    for kv in args {
        if kv == "nodrift" {
            o.drift = false;
            continue;
        }
        if kv == "dynamic" {
            o.remove_wall_at = Some(3500);
            continue;
        }
        let (k, v) = kv.split_once('=').expect("k=v");
        o.params.set(k, v).expect("param");
    }
    let r = run(&o).expect("run");
    println!(
        "seed {} drift {:.3} rot {:.2} deg/m dist {:.0} m wall {:.1}s eq {:?} gap {:?}",
        seed,
        r.trans_drift,
        r.rot_drift_deg_per_m,
        r.distance_m,
        r.wall_s,
        r.equilibrium_at,
        r.gap_closed_after
    );
    println!("{:?}", r.stats);
    for c in &r.checkpoints {
        println!("{:6} cells {:4} edges {:4} conf {:.2} abs {:.2} oabs {:.2} err {:.3} hd {:6.1} odo {:.3} spread {:.3} cross {:.2} unreach {:.2} gap {:?}", c.sample, c.cells, c.edges, c.mean_confidence, c.absolute_error_m, c.odometry_absolute_m, c.aligned_error_m, c.heading_error_deg, c.odometry_error_m, c.place_spread_m, c.crossings_per_edge, c.unreachable, c.gap_edges);
    }
}
