use emulator::alice::arena::alice;
use emulator::alice::sensors::Sensors;
use emulator::geometry::Point;
use emulator::rng::SimRng;
use world_model::situation::{axis_difference, principal_axis, ring_shift, rotate_to_world};
fn main() {
    let a = alice();
    let walls = a.segment_set();
    let mut s = Sensors::new(SimRng::new(1, 102));
    let mut rng = SimRng::new(5, 1);
    let (mut sum, mut sum2, mut n, mut asum2) = (0.0, 0.0, 0, 0.0);
    for _ in 0..2000 {
        let p = Point::new(0.4 + 2.2 * rng.uniform(), 0.4 + 2.2 * rng.uniform());
        if walls.circle_collides(p, 0.2) {
            continue;
        }
        let q = Point::new(
            p.x + 0.1 * (rng.uniform() - 0.5),
            p.y + 0.1 * (rng.uniform() - 0.5),
        );
        let (h1, h2) = (6.28 * rng.uniform(), 6.28 * rng.uniform());
        let l1 = s.light(&walls, &a.lights, p, h1);
        let l2 = s.light(&walls, &a.lights, q, h2);
        let (mut w1, mut w2) = (Vec::new(), Vec::new());
        rotate_to_world(&l1, h1, &mut w1);
        rotate_to_world(&l2, h2, &mut w2);
        if let Some(d) = ring_shift(&w1, &w2, 0.5, 0.25) {
            sum += d;
            sum2 += d * d;
            n += 1;
        }
        if let (Some((x, _)), Some((y, _))) = (principal_axis(&w1), principal_axis(&w2)) {
            asum2 += axis_difference(x, y).powi(2);
        }
    }
    println!(
        "n {n} mean {:.2} deg rms {:.2} deg axis rms {:.2} deg",
        (sum / n as f64).to_degrees(),
        (sum2 / n as f64).sqrt().to_degrees(),
        (asum2 / n as f64).sqrt().to_degrees()
    );
}
