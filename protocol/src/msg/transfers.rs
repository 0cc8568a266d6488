//! Chunked transfer frames (PROTOCOL.md §8): begin, data, acknowledgement and status; the
//! state machines that use them are `crate::transfer`.

use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

/// The objects that move by chunked transfer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub enum ObjectKind {
    Map,
    Plan,
    Regions,
    /// Seed 000 §5.3's light -> angle network (60 neurons x 6 inputs, in hundredths): trained
    /// on the robot (`Mode::CalibrateLight`) or by `station calibrate`, and moved either way.
    LightCalibration,
}

/// Sender -> receiver: an object of `len` bytes with CRC-32C `crc` follows in chunks.
/// `id` names the content (the station uses its CRC-32C of the content) so a receiver that
/// already holds it answers `AlreadyHave` and nothing is sent again. `tag` (1..=255, chosen
/// by the sender, different from its previous transfer's) names this transfer in its
/// `TransferData` chunks and in the receiver's answers: one byte instead of the 5-byte id in
/// every chunk. Last, so a build from before tags reads this frame as one with a trailing
/// byte and refuses it ("undecodable payload"), never as another Begin.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct TransferBegin {
    pub object: ObjectKind,
    pub id: u32,
    pub len: u32,
    pub crc: u32,
    pub tag: u8,
}

/// Kind 8, retired: protocol 1's chunk, which named the object by its 32-bit id and carried
/// a length. Still decoded (recordings made before tags hold it) and never sent; the robot
/// refuses it (`TransferAck` with tag 0, `Rejected`) and changes nothing, the station ignores
/// it. Chunks are [`TransferData`] (kind 17).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct TransferChunk<'a> {
    pub id: u32,
    pub offset: u32,
    pub data: &'a [u8],
}

/// Receiver -> sender: every byte before `next` of the transfer `tag` is held (cumulative
/// ack), and bit i of `sack` says the 32-byte unit `[next + 32 i, next + 32 i + 32)` past it
/// is held too (selective ack, PROTOCOL.md §8; 0 in every answer but `Receiving`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub struct TransferAck {
    pub tag: u8,
    pub next: u32,
    pub status: TransferStatus,
    pub sack: u32,
}

/// Sender -> receiver (kind 17): `data` belongs at `offset` of the transfer whose
/// `TransferBegin` carried `tag`. `data` runs to the end of the payload, with no length of
/// its own (the frame's delimiter bounds it): the payload is `tag`, `offset` as a varint,
/// then the bytes. Serialized and decoded by hand for that reason (`frame::decode_payload`);
/// serde's `Deserialize` cannot know where the data ends and refuses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TransferData<'a> {
    pub tag: u8,
    pub offset: u32,
    pub data: &'a [u8],
}

impl Serialize for TransferData<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeTuple;
        // A tuple has no length on the wire (postcard): tag, offset, then the bytes as they are.
        let mut t = s.serialize_tuple(2 + self.data.len())?;
        t.serialize_element(&self.tag)?;
        t.serialize_element(&self.offset)?;
        for b in self.data {
            t.serialize_element(b)?;
        }
        t.end()
    }
}

impl<'de> Deserialize<'de> for TransferData<'_> {
    fn deserialize<D: serde::Deserializer<'de>>(_: D) -> Result<Self, D::Error> {
        Err(serde::de::Error::custom(
            "TransferData's data runs to the end of the frame: decode it with frame::decode_payload",
        ))
    }
}

impl Schema for TransferData<'_> {
    const SCHEMA: &'static postcard_schema::schema::NamedType =
        &postcard_schema::schema::NamedType {
            name: "TransferData",
            ty: &postcard_schema::schema::DataModelType::Struct(&[
                &postcard_schema::schema::NamedValue {
                    name: "tag",
                    ty: u8::SCHEMA,
                },
                &postcard_schema::schema::NamedValue {
                    name: "offset",
                    ty: u32::SCHEMA,
                },
                &postcard_schema::schema::NamedValue {
                    name: "data",
                    ty: &postcard_schema::schema::NamedType {
                        name: "rest of the payload",
                        ty: &postcard_schema::schema::DataModelType::Seq(u8::SCHEMA),
                    },
                },
            ]),
        };
}

/// State of a transfer at the receiver.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Schema)]
pub enum TransferStatus {
    /// Send from `next` on.
    Receiving,
    /// All bytes arrived, the CRC matched and the object is installed.
    Complete,
    /// The receiver already holds this id; nothing to send.
    AlreadyHave,
    /// All bytes arrived but the CRC did not match; the old object is kept. Start again.
    CrcMismatch,
    /// The object is larger than the receiver can hold, or malformed.
    Rejected,
    /// A chunk or ack named an id that is not the transfer in progress.
    UnknownId,
    /// The receiver cannot take this object now (the robot is calibrating the network the
    /// object would replace); nothing was changed. Try again later.
    Busy,
}
