//! The LightCalibration object (PROTOCOL.md §12): seed 000 §5.3's light -> angle network, the
//! robot's own storage (u16 hundredths) laid out neuron by neuron.
//!
//! Invariants: a parsed object has exactly [`LIGHT_NEURONS`] neurons of [`LIGHT_INPUTS`]
//! weights each, and every output (the light's angle + 90 deg) is within 0..=180 deg. Weights
//! may be any u16: the firmware's rescaled readings are 50..500, but a neuron that never won
//! keeps whatever it was drawn with, so a bound would refuse honest networks.

use super::{
    check_len, check_prefix, output, put, u16_at, u8_at, ObjectError, Problem, OBJECT_VERSION,
};
use crate::msg::ObjectKind;

/// Neurons in the network (seed 000 §5.3).
pub const LIGHT_NEURONS: usize = 60;
/// Inputs per neuron: the front sensors S0..S5.
pub const LIGHT_INPUTS: usize = 6;
/// Bytes before the first neuron.
pub const LIGHT_HEADER_LEN: usize = 4;
/// Bytes per neuron: its weights and its output, u16 each.
pub const LIGHT_NEURON_LEN: usize = 2 * (LIGHT_INPUTS + 1);
/// Bytes of the whole object.
pub const LIGHT_OBJECT_LEN: usize = LIGHT_HEADER_LEN + LIGHT_NEURONS * LIGHT_NEURON_LEN;
/// Largest output, hundredths of a degree: the angle + 90 deg spans 0..=180 deg.
pub const LIGHT_MAX_OUTPUT: u16 = 18_000;

/// One neuron: its weights (rescaled readings) and its output (angle + 90 deg), hundredths.
pub type LightNeuron = ([u16; LIGHT_INPUTS], u16);

fn neuron_at(i: usize) -> usize {
    LIGHT_HEADER_LEN + i * LIGHT_NEURON_LEN
}

/// Encodes a network given neuron by neuron (exactly [`LIGHT_NEURONS`] of them).
pub fn encode_light<I>(neurons: I, out: &mut [u8]) -> Result<usize, ObjectError>
where
    I: IntoIterator<Item = LightNeuron>,
    I::IntoIter: ExactSizeIterator,
{
    let neurons = neurons.into_iter();
    if neurons.len() != LIGHT_NEURONS {
        return Err(ObjectError::at(2, Problem::CountMismatch));
    }
    let out = output(out, LIGHT_OBJECT_LEN)?;
    put(
        out,
        0,
        &[
            OBJECT_VERSION,
            ObjectKind::LightCalibration as u8,
            LIGHT_NEURONS as u8,
            LIGHT_INPUTS as u8,
        ],
    );
    for (i, (weights, output)) in neurons.enumerate() {
        let at = neuron_at(i);
        check_output(output, i)?;
        for (k, w) in weights.iter().enumerate() {
            put(out, at + 2 * k, &w.to_le_bytes());
        }
        put(out, at + 2 * LIGHT_INPUTS, &output.to_le_bytes());
    }
    Ok(LIGHT_OBJECT_LEN)
}

fn check_output(output: u16, index: usize) -> Result<(), ObjectError> {
    if output > LIGHT_MAX_OUTPUT {
        let at = neuron_at(index) + 2 * LIGHT_INPUTS;
        let index = u16::try_from(index).unwrap_or(u16::MAX);
        return Err(ObjectError::at(at, Problem::BadOutput { index, output }));
    }
    Ok(())
}

/// A parsed LightCalibration object.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightView<'a> {
    bytes: &'a [u8],
}

impl<'a> LightView<'a> {
    /// Checks `bytes` as a LightCalibration object: shape, length and every output.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, ObjectError> {
        check_prefix(bytes, ObjectKind::LightCalibration)?;
        let (neurons, inputs) = (u8_at(bytes, 2)?, u8_at(bytes, 3)?);
        if usize::from(neurons) != LIGHT_NEURONS || usize::from(inputs) != LIGHT_INPUTS {
            return Err(ObjectError::at(2, Problem::BadShape { neurons, inputs }));
        }
        check_len(bytes.len(), LIGHT_OBJECT_LEN)?;
        let view = LightView { bytes };
        for i in 0..LIGHT_NEURONS {
            check_output(u16_at(bytes, neuron_at(i) + 2 * LIGHT_INPUTS)?, i)?;
        }
        Ok(view)
    }

    /// Neuron `i`: its weights and output in hundredths.
    pub fn neuron(&self, i: usize) -> Option<LightNeuron> {
        if i >= LIGHT_NEURONS {
            return None;
        }
        let at = neuron_at(i);
        let mut weights = [0u16; LIGHT_INPUTS];
        for (k, w) in weights.iter_mut().enumerate() {
            *w = u16_at(self.bytes, at + 2 * k).ok()?;
        }
        Some((weights, u16_at(self.bytes, at + 2 * LIGHT_INPUTS).ok()?))
    }

    /// The neurons in chain order.
    pub fn neurons(&self) -> impl Iterator<Item = LightNeuron> + 'a {
        let view = *self;
        (0..LIGHT_NEURONS).filter_map(move |i| view.neuron(i))
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn network() -> impl ExactSizeIterator<Item = LightNeuron> {
        (0..LIGHT_NEURONS as u16).map(|i| ([5000 + i, 10, 20, 30, 40, 50_000], i * 300))
    }

    #[test]
    fn encodes_and_parses_back_the_same_neurons() {
        let mut buf = [0u8; LIGHT_OBJECT_LEN];
        assert_eq!(encode_light(network(), &mut buf), Ok(LIGHT_OBJECT_LEN));
        assert_eq!(&buf[..4], &[1, 3, 60, 6]);
        let v = LightView::parse(&buf).unwrap();
        assert!(v.neurons().eq(network()));
        assert_eq!(v.neuron(60), None);
    }

    #[test]
    fn refuses_a_wrong_shape_an_output_past_180_deg_and_a_wrong_length() {
        let mut buf = [0u8; LIGHT_OBJECT_LEN + 1];
        encode_light(network(), &mut buf).unwrap();
        let ok = &buf[..LIGHT_OBJECT_LEN];
        let mut shape = ok.to_vec();
        shape[3] = 7;
        let e = LightView::parse(&shape).unwrap_err();
        assert_eq!(
            e,
            ObjectError::at(
                2,
                Problem::BadShape {
                    neurons: 60,
                    inputs: 7
                }
            )
        );
        let mut out = ok.to_vec();
        let at = neuron_at(59) + 12;
        out[at..at + 2].copy_from_slice(&18_001u16.to_le_bytes());
        let e = LightView::parse(&out).unwrap_err();
        assert_eq!(e.offset, at);
        assert_eq!(
            e.problem,
            Problem::BadOutput {
                index: 59,
                output: 18_001
            }
        );
        assert!(matches!(
            LightView::parse(&buf).unwrap_err().problem,
            Problem::TrailingBytes { extra: 1 }
        ));
        assert!(matches!(
            LightView::parse(&ok[..100]).unwrap_err().problem,
            Problem::Truncated { .. }
        ));
        assert_eq!(
            encode_light(network().take(59), &mut buf)
                .unwrap_err()
                .problem,
            Problem::CountMismatch
        );
    }
}
