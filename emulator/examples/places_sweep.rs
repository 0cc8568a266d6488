//! Seed 003 ch. 3 over seeds: one summary line per run and the medians, for measuring what
//! a change does (`cargo run --release -p emulator --example places_sweep -- structured 1 10`,
//! optional 4th argument: seconds). Variants by environment: FUSION=off (the thesis's reset,
//! gain 1), WHEEL_HEADING=1 (heading from the wheels; HEADING=stored|compass|keep at matches),
//! MATCH_SIGMA (diameters), COMPASS_DEG, MOTORS, THRESH, LEV_SCALE, NOEXC=1, IR=khepera (the
//! real robot's 3.3 cm IR curve instead of the thesis's 5 cm).
#![allow(clippy::unwrap_used)]

use emulator::scenarios::unsupervised_places::{run, ArenaKind, PlacesOptions};

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let kind = ArenaKind::parse(a.get(1).map_or("unstructured", String::as_str)).unwrap();
    let lo: u64 = a.get(2).map_or(1, |s| s.parse().unwrap());
    let hi: u64 = a.get(3).map_or(10, |s| s.parse().unwrap());
    let dur: f64 = a.get(4).map_or(1200.0, |s| s.parse().unwrap());
    let mut peaks = Vec::new();
    for seed in lo..=hi {
        let mut o = PlacesOptions::new(kind, seed);
        o.duration_s = dur;
        if let Ok(v) = std::env::var("LEV_SCALE") {
            o.landmarks.lev_scale = v.parse().unwrap();
        }
        if let Ok(v) = std::env::var("THRESH") {
            o.landmarks.match_threshold = v.parse().unwrap();
        }
        if let Ok(v) = std::env::var("MOTORS") {
            o.noise.motors = v.parse().unwrap();
        }
        if std::env::var("NOEXC").is_ok_and(|v| !v.is_empty()) {
            o.excursions = false;
        }
        if let Ok(v) = std::env::var("HEADING") {
            o.heading_reset = match v.as_str() {
                "compass" => emulator::scenarios::unsupervised_places::HeadingReset::Compass,
                "keep" => emulator::scenarios::unsupervised_places::HeadingReset::Keep,
                _ => emulator::scenarios::unsupervised_places::HeadingReset::Stored,
            };
        }
        if let Ok(v) = std::env::var("COMPASS_DEG") {
            o.noise.compass_deg = v.parse().unwrap();
        }
        if std::env::var("IR").is_ok_and(|v| v == "khepera") {
            o.ir_curve = emulator::sensors::ir::IrCurve::KHEPERA;
        }
        if std::env::var("FUSION").is_ok_and(|v| v == "off") {
            o.fusion = None;
        }
        if std::env::var("WHEEL_HEADING").is_ok_and(|v| !v.is_empty()) {
            o.compass_heading = false;
        }
        if let Ok(v) = std::env::var("MATCH_SIGMA") {
            if let Some(f) = o.fusion.as_mut() {
                f.match_sigma_m = v.parse::<f32>().unwrap() * 0.055;
            }
        }
        let r = run(&o);
        // The landmarks' own error when made (truth), by quarter of their making order.
        let made: Vec<f64> = r
            .landmark_positions
            .iter()
            .zip(&r.landmark_truth)
            .map(|(p, t)| (p[0] - t[0]).hypot(p[1] - t[1]) / 0.055)
            .collect();
        let q = made.len() / 4;
        let quarters: Vec<f64> = (0..4)
            .map(|i| {
                let part = &made[i * q..if i == 3 { made.len() } else { (i + 1) * q }];
                (part.iter().sum::<f64>() / part.len().max(1) as f64 * 100.0).round() / 100.0
            })
            .collect();
        println!(
            "seed {seed:>2}: landmark error when made, by quarter of making order: {quarters:?}"
        );
        let n = r.match_log.len().max(1) as f64;
        println!(
            "seed {seed:>2}: three estimates, peak/mean diameters: plain {:5.2}/{:5.2} compass {:4.2}/{:4.2} compass+landmarks {:4.2}/{:4.2} | matches {} mean gain {:.2} landmark err mean {:.2} max {:.2} worse {}",
            r.plain_peak, r.plain_mean, r.compass_peak, r.compass_mean, r.corrected_peak, r.corrected_mean,
            r.matches,
            r.match_log.iter().map(|m| m.gain).sum::<f64>() / n,
            r.match_log.iter().map(|m| m.landmark_err).sum::<f64>() / n,
            r.match_log.iter().map(|m| m.landmark_err).fold(0.0, f64::max),
            r.worsening_matches
        );
        let d = r.revisit;
        println!(
            "seed {seed:>2}: lm {:>3} match {:>4} worse {:>3} | peak corr {:5.2} (after60 {:5.2}) plain {:5.2} compass {:4.2} mean corr {:4.2} | kernels {:>4} near {:>4} revisit {:>4} matched {:>3} toofar {:>3} samedir {:>4} lev {:?} levsame {:?} odo {:.2} | stats {:?}",
            r.landmarks, r.matches, r.worsening_matches, r.corrected_peak, r.corrected_peak_after_60s,
            r.plain_peak, r.compass_peak, r.corrected_mean, d.kernels, d.near_any_landmark, d.revisits,
            d.revisits_matched, d.revisits_too_far, d.revisits_same_direction,
            d.revisit_lev.map(|x| (x * 10.0).round() / 10.0),
            d.revisit_lev_same_direction.map(|x| (x * 10.0).round() / 10.0),
            d.revisit_odo_dist, r.match_stats
        );
        println!(
            "         impostors {} lev {:?} | matches {} offset mean {:.2} over half {}",
            d.impostors,
            d.impostor_lev.map(|x| (x * 10.0).round() / 10.0),
            d.matches,
            d.match_offset_mean,
            d.match_offset_over_half
        );
        let l = r.loss;
        println!(
            "         loss: peak {:.2} lost_at {:?} after {} | matches {} wrong {} (offset mean {:.2} max {:.2}, error change {:+.2}) offset mean {:.2} | gap mean {:.0} s max {:.0} s, drift between mean {:.2} max {:.2}, err before {:.2} after {:.2} | landmarks {} spacing {:.2} same-kernel {:.2} alias pairs {} made err {:.2}/{:.2} | classes {:?} significant {:?} | gate-ignored revisits {} of {}",
            r.corrected_peak, l.lost_at_s, l.matches_after_lost, l.matches, l.wrong_matches,
            l.wrong_offset_mean, l.wrong_offset_max, l.wrong_error_change_mean, l.offset_mean,
            l.gap_mean_s, l.gap_max_s, l.drift_between_mean, l.drift_between_max,
            l.err_before_mean, l.err_after_mean, l.landmarks, l.spacing_mean,
            l.same_kernel_spacing_mean, l.alias_pairs, l.made_err_mean, l.made_err_max,
            r.classes, r.significant_classes, d.revisits_too_far, d.revisits
        );
        peaks.push((r.corrected_peak, r.landmarks));
    }
    peaks.sort_by(|a, b| a.0.total_cmp(&b.0));
    println!(
        "corrected peaks sorted: {:?}",
        peaks
            .iter()
            .map(|p| (p.0 * 100.0).round() / 100.0)
            .collect::<Vec<_>>()
    );
}
