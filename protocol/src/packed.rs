//! Eight 10-bit sensor readings packed into 10 bytes.
//!
//! The Khepera's IR and ambient-light sensors read 0..=1023 (seed 000 §1.1). As postcard
//! varints, eight such values take up to 16 bytes; packed they always take 10, which is what
//! keeps a full telemetry frame under 80 bytes on the wire. Bit order: value `i` occupies bits
//! `10*i .. 10*i+9` of the little-endian 80-bit integer formed by the 10 bytes (byte 0 holds
//! bits 0..7). Every 10-byte pattern decodes to valid values, so decoding cannot fail.

use postcard_schema::{schema::NamedType, Schema};
use serde::de::{Error as _, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// Number of bytes on the wire.
pub const PACKED_LEN: usize = 10;
/// Largest value a slot holds.
pub const MAX_10BIT: u16 = 1023;

/// Eight 10-bit readings. Values above 1023 saturate to 1023 when set.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Packed10x8([u16; 8]);

impl Packed10x8 {
    /// Packs eight readings, saturating each at 1023.
    pub fn new(values: [u16; 8]) -> Self {
        Packed10x8(values.map(|v| v.min(MAX_10BIT)))
    }

    /// The eight readings.
    pub fn values(&self) -> [u16; 8] {
        self.0
    }

    /// The wire form.
    pub fn to_bytes(&self) -> [u8; PACKED_LEN] {
        let mut acc: u128 = 0;
        for (i, v) in self.0.iter().enumerate() {
            acc |= u128::from(*v & MAX_10BIT) << (10 * i);
        }
        let le = acc.to_le_bytes();
        let mut out = [0u8; PACKED_LEN];
        out.copy_from_slice(&le[..PACKED_LEN]);
        out
    }

    /// Reads the wire form.
    pub fn from_bytes(bytes: [u8; PACKED_LEN]) -> Self {
        let mut le = [0u8; 16];
        le[..PACKED_LEN].copy_from_slice(&bytes);
        let acc = u128::from_le_bytes(le);
        let mut values = [0u16; 8];
        for (i, v) in values.iter_mut().enumerate() {
            // Masked to 10 bits, so the narrowing cannot lose anything.
            *v = ((acc >> (10 * i)) & u128::from(MAX_10BIT)) as u16;
        }
        Packed10x8(values)
    }
}

impl Serialize for Packed10x8 {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        // A fixed-size array is a tuple to serde: postcard writes the bytes with no length.
        self.to_bytes().serialize(serializer)
    }
}

impl<'de> Deserialize<'de> for Packed10x8 {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct BytesVisitor;
        impl<'de> Visitor<'de> for BytesVisitor {
            type Value = [u8; PACKED_LEN];
            fn expecting(&self, f: &mut core::fmt::Formatter) -> core::fmt::Result {
                f.write_str("10 bytes of packed 10-bit readings")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
                let mut out = [0u8; PACKED_LEN];
                for (i, b) in out.iter_mut().enumerate() {
                    *b = seq
                        .next_element()?
                        .ok_or_else(|| A::Error::invalid_length(i, &self))?;
                }
                Ok(out)
            }
        }
        let bytes = deserializer.deserialize_tuple(PACKED_LEN, BytesVisitor)?;
        Ok(Packed10x8::from_bytes(bytes))
    }
}

impl Schema for Packed10x8 {
    const SCHEMA: &'static NamedType = &NamedType {
        name: "Packed10x8",
        ty: <[u8; PACKED_LEN] as Schema>::SCHEMA.ty,
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packing_round_trips_and_saturates() {
        let p = Packed10x8::new([0, 1, 2, 1023, 512, 1024, 65535, 77]);
        assert_eq!(p.values(), [0, 1, 2, 1023, 512, 1023, 1023, 77]);
        assert_eq!(Packed10x8::from_bytes(p.to_bytes()), p);
    }

    #[test]
    fn bit_layout_is_little_endian_by_slot() {
        let p = Packed10x8::new([0x3FF, 0, 0, 0, 0, 0, 0, 1]);
        // Slot 0 fills byte 0 and the low 2 bits of byte 1; slot 7 starts at bit 70.
        assert_eq!(
            p.to_bytes(),
            [0xFF, 0x03, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x40, 0x00]
        );
    }
}
