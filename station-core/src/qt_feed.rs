//! The link's half of the QT world model: an ALICE's situation (message kind 16) turned into
//! the model's `Sample` and fed to `app.qt`.
//!
//! Layer: state only, no I/O. The wire carries integers (PROTOCOL.md §6 kind 16): light
//! 0..=255, whisker bits, the odometry pose in millimetres and milliradians; the model wants
//! 0..1 readings, booleans and metres.

use protocol::{AliceSituation, ALICE_SENSORS};
use world_model::{Pose, Sample};

use crate::qt_state::QtState;

/// The model's inputs decoded from one situation: light 0..1, touches, pose in metres.
pub fn sample_parts(s: &AliceSituation) -> ([f64; ALICE_SENSORS], [bool; ALICE_SENSORS], Pose) {
    let light = s.light.map(|v| f64::from(v) / 255.0);
    let mut touch = [false; ALICE_SENSORS];
    for (i, t) in touch.iter_mut().enumerate() {
        *t = s.whiskers & (1 << i) != 0;
    }
    let pose = Pose {
        x: f64::from(s.odometry.x_mm) / 1000.0,
        y: f64::from(s.odometry.y_mm) / 1000.0,
        heading: f64::from(s.odometry.heading_mrad) / 1000.0,
    };
    (light, touch, pose)
}

impl QtState {
    /// One situation from the link: count gaps in its sequence, then feed the model. A
    /// refusal (a model that cannot be made with `params`, or readings it rejects) is
    /// counted in `refused` with its reason; the link goes on.
    pub fn on_situation(&mut self, s: &AliceSituation) {
        self.received += 1;
        if let Some(prev) = self.last_seq {
            // A wrapping gap: frames lost between the two (a repeat counts nothing).
            let gap = s.seq.wrapping_sub(prev).wrapping_sub(1);
            if gap < u16::MAX / 2 {
                self.lost += u64::from(gap);
            }
        }
        self.last_seq = Some(s.seq);
        self.last = Some(*s);
        let (light, touch, odometry) = sample_parts(s);
        let params = self.params.clone();
        let sample = Sample {
            light: &light,
            touch: &touch,
            odometry,
        };
        if let Err(e) = self.feed(&params, &sample) {
            if self.model.is_none() {
                self.refused += 1;
                self.last_error = Some(e.to_string());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn situation(seq: u16, x_mm: i32) -> AliceSituation {
        let mut light = [0u8; ALICE_SENSORS];
        for (i, v) in light.iter_mut().enumerate() {
            *v = (i * 10) as u8;
        }
        AliceSituation {
            time_ms: u32::from(seq) * 333,
            seq,
            whiskers: 0b101,
            light,
            odometry: protocol::Pose {
                x_mm,
                y_mm: -250,
                heading_mrad: 1571,
            },
        }
    }

    #[test]
    fn wire_units_become_the_models() {
        let (light, touch, pose) = sample_parts(&situation(0, 1500));
        assert_eq!(light[0], 0.0);
        assert!((light[23] - 230.0 / 255.0).abs() < 1e-12);
        assert_eq!(&touch[..4], &[true, false, true, false]);
        assert!(touch[3..].iter().all(|t| !t));
        assert_eq!((pose.x, pose.y), (1.5, -0.25));
        assert!((pose.heading - 1.571).abs() < 1e-12);
    }

    #[test]
    fn situations_grow_the_model_and_gaps_are_counted() {
        let mut qt = QtState::default();
        assert!(!qt.active());
        for (k, seq) in [0u16, 1, 2, 5, 6].into_iter().enumerate() {
            qt.on_situation(&situation(seq, 100 * k as i32));
        }
        assert!(qt.active());
        assert_eq!(qt.received, 5);
        assert_eq!(qt.lost, 2);
        assert_eq!(qt.model.as_ref().map(|m| m.stats().samples), Some(5));
        // Sequence wraps without a loss.
        let mut qt = QtState::default();
        qt.on_situation(&situation(u16::MAX, 0));
        qt.on_situation(&situation(0, 10));
        assert_eq!(qt.lost, 0);
    }
}
