//! The station's QT world model (seed 001 ch. 4-5, `world_model`): it runs here, not on the
//! robot, because it needs a heap and far more memory than a 32 KB robot (docs/reproductions.md,
//! the ALICE rows). Fed one situation at a time (light ring, whiskers, odometry pose); the map's
//! `qt` layer draws it.
//!
//! Layer: state only, no I/O. The feed from the wire (message kind 16, the robot's
//! situation) is `qt_feed`, which calls `feed`.

use world_model::{ParamError, Params, Pose, QtModel, Sample};

/// The model, made on the first situation.
#[derive(Clone, Debug, Default)]
pub struct QtState {
    /// The model; `None` until a situation arrived.
    pub model: Option<QtModel>,
    /// Situations refused (wrong reading counts, non-finite values), with the last reason.
    pub refused: u64,
    /// Why the last one was refused.
    pub last_error: Option<String>,
    /// The parameters a model is made with (`world_model::Params` defaults).
    pub params: Params,
    /// Situations received from the link (kind 16), fed or refused (`qt_feed`).
    pub received: u64,
    /// Situations lost on the wire, from the gaps in their sequence numbers.
    pub lost: u64,
    /// The last situation's sequence number.
    pub last_seq: Option<u16>,
    /// The last situation (the sensor panel draws ALICE's whiskers and photoresistors).
    pub last: Option<protocol::AliceSituation>,
}

impl QtState {
    /// Integrate one situation; the model starts at its odometry pose with `params`.
    pub fn feed(&mut self, params: &Params, sample: &Sample) -> Result<(), ParamError> {
        let model = match &mut self.model {
            Some(m) => m,
            None => {
                let start = Pose { ..sample.odometry };
                self.model.insert(QtModel::new(params.clone(), start)?)
            }
        };
        let r = model.observe(sample);
        if let Err(e) = &r {
            self.refused += 1;
            self.last_error = Some(e.to_string());
        }
        r
    }

    /// True once the model has cells to draw.
    pub fn active(&self) -> bool {
        self.model.as_ref().is_some_and(|m| !m.network().is_empty())
    }
}
