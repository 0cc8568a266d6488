//! The byte format: the header and records encoded and parsed over byte slices, no I/O.

use super::{
    LinkState, Meta, ReadError, Record, RecordKind, HEADER_FIXED, MAGIC, MAX_DATA, MAX_LINKS,
    MAX_META, MAX_T_US, OLDEST_VERSION, VERSION,
};

/// A record's time at byte `at`, after one at `last_t`: never earlier, and at most
/// `MAX_T_US`. Every reader of records checks it (`Recording::parse`, the retrace's loader).
pub fn check_time(last_t: u64, t_us: u64, at: usize) -> Result<(), ReadError> {
    let why = if t_us < last_t {
        format!("time goes back from {last_t} us to {t_us} us")
    } else if t_us > MAX_T_US {
        format!("time {t_us} us is more than a year ({MAX_T_US} us) after the recording's start")
    } else {
        return Ok(());
    };
    Err(ReadError::BadRecord {
        offset: at as u64,
        why,
    })
}

/// CRC-32C of a record: `protocol::crc32c`, computed 16 bytes a step (a 16 KB table; the
/// protocol's own takes one byte a step with 1 KB, small enough for the robot). Reading a
/// recording checks every record's CRC; byte by byte that was a third of a replay.
pub fn record_crc(bytes: &[u8]) -> u32 {
    const CRC: crc::Crc<u32, crc::Table<16>> =
        crc::Crc::<u32, crc::Table<16>>::new(&crc::CRC_32_ISCSI);
    CRC.checksum(bytes)
}

/// The header's bytes (version 2). A meta without `links` is given one link, its `port`.
pub fn encode_header(meta: &Meta) -> Vec<u8> {
    let mut meta = meta.clone();
    if meta.links.is_empty() {
        meta.links = vec![meta.port.clone()];
    }
    let json = serde_json::to_vec(&meta).unwrap_or_else(|_| b"{}".to_vec());
    let mut out = Vec::with_capacity(HEADER_FIXED + json.len() + 4);
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&0u16.to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&json);
    let crc = protocol::crc32c(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    out
}

/// Appends one record's bytes (version 2) to `out`. Data longer than `MAX_DATA` must be split
/// by the caller (`writer` does).
pub fn encode_record(out: &mut Vec<u8>, t_us: u64, kind: RecordKind, link: u8, data: &[u8]) {
    let start = out.len();
    put_varint(out, t_us);
    out.push(kind.code());
    out.push(link);
    put_varint(out, data.len() as u64);
    out.extend_from_slice(data);
    let crc = record_crc(out.get(start..).unwrap_or(&[]));
    out.extend_from_slice(&crc.to_le_bytes());
}

pub(super) fn put_varint(out: &mut Vec<u8>, mut v: u64) {
    loop {
        let b = (v & 0x7f) as u8;
        v >>= 7;
        if v == 0 {
            out.push(b);
            return;
        }
        out.push(b | 0x80);
    }
}

/// Reads a varint at `at`: the value and the next offset. `Ok(None)` when the input ends.
fn get_varint(bytes: &[u8], at: usize) -> Result<Option<(u64, usize)>, String> {
    let mut v = 0u64;
    for i in 0..10 {
        let Some(&b) = bytes.get(at + i) else {
            return Ok(None);
        };
        let part = u64::from(b & 0x7f);
        if i == 9 && part > 1 {
            return Err("varint overflows 64 bits".into());
        }
        v |= part << (7 * i);
        if b & 0x80 == 0 {
            return Ok(Some((v, at + i + 1)));
        }
    }
    Err("varint longer than 10 bytes".into())
}

fn le_u16(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(b.get(at..at + 2)?.try_into().ok()?))
}

fn le_u32(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}

/// What the header says: the format version and the metadata.
#[derive(Clone, Debug, PartialEq)]
pub struct Header {
    pub version: u16,
    pub meta: Meta,
}

/// Parses the header: the version, the metadata and the offset of the first record.
pub fn parse_header(bytes: &[u8]) -> Result<(Header, usize), ReadError> {
    let short = |offset: usize| ReadError::BadHeader {
        offset: offset as u64,
        why: "the file ends inside the header".into(),
    };
    match bytes.get(..MAGIC.len()) {
        Some(m) if m == MAGIC => {}
        Some(_) => return Err(ReadError::NotARecording),
        None if MAGIC.starts_with(bytes) && !bytes.is_empty() => return Err(short(bytes.len())),
        None => return Err(ReadError::NotARecording),
    }
    let version = le_u16(bytes, 8).ok_or_else(|| short(bytes.len()))?;
    if !(OLDEST_VERSION..=VERSION).contains(&version) {
        return Err(ReadError::UnsupportedVersion { version });
    }
    let meta_len = le_u32(bytes, 12).ok_or_else(|| short(bytes.len()))? as usize;
    if meta_len > MAX_META {
        return Err(ReadError::BadHeader {
            offset: 12,
            why: format!("metadata length {meta_len} is over {MAX_META}"),
        });
    }
    let crc_at = HEADER_FIXED + meta_len;
    let stored = le_u32(bytes, crc_at).ok_or_else(|| short(bytes.len()))?;
    let covered = bytes.get(..crc_at).ok_or_else(|| short(bytes.len()))?;
    let computed = protocol::crc32c(covered);
    if stored != computed {
        return Err(ReadError::BadHeader {
            offset: crc_at as u64,
            why: format!("header CRC {stored:08x} stored, {computed:08x} computed"),
        });
    }
    let json = bytes.get(HEADER_FIXED..crc_at).unwrap_or(&[]);
    let meta: Meta = serde_json::from_slice(json).map_err(|e| ReadError::BadHeader {
        offset: HEADER_FIXED as u64,
        why: format!("metadata is not a JSON object: {e}"),
    })?;
    // Version 2 names its links: record link ids are checked against them.
    if version >= 2 && !(1..=MAX_LINKS).contains(&meta.links.len()) {
        return Err(ReadError::BadHeader {
            offset: HEADER_FIXED as u64,
            why: format!(
                "metadata names {} links; a version {version} recording names 1 to {MAX_LINKS}",
                meta.links.len()
            ),
        });
    }
    Ok((Header { version, meta }, crc_at + 4))
}

/// Parses the record at `at` of a file of format `version` with `links` links: the record and
/// the offset after it.
pub fn parse_record(
    bytes: &[u8],
    at: usize,
    version: u16,
    links: usize,
) -> Result<(Record, usize), ReadError> {
    let offset = at as u64;
    let bad = |why: String| ReadError::BadRecord { offset, why };
    let truncated = ReadError::Truncated { offset };
    let (t_us, p) = get_varint(bytes, at)
        .map_err(bad)?
        .ok_or(truncated.clone())?;
    let code = *bytes.get(p).ok_or(truncated.clone())?;
    let (link, p) = if version >= 2 {
        (*bytes.get(p + 1).ok_or(truncated.clone())?, p + 2)
    } else {
        (0, p + 1)
    };
    let (len, p) = get_varint(bytes, p)
        .map_err(bad)?
        .ok_or(truncated.clone())?;
    let len = usize::try_from(len).unwrap_or(usize::MAX);
    if len > MAX_DATA {
        return Err(bad(format!("record length {len} is over {MAX_DATA}")));
    }
    let data = bytes.get(p..p + len).ok_or(truncated.clone())?;
    let stored = le_u32(bytes, p + len).ok_or(truncated)?;
    let computed = record_crc(bytes.get(at..p + len).unwrap_or(&[]));
    if stored != computed {
        return Err(ReadError::BadCrc {
            offset,
            stored,
            computed,
        });
    }
    let kind = RecordKind::from_code(code);
    // After the CRC: a wrong id in a record whose bytes are intact is a writer's fault (or a
    // forgery), named as such; a damaged byte is a CRC error like any other.
    if usize::from(link) >= links {
        return Err(bad(format!(
            "link id {link}, but the header names {links} link(s) (ids 0 to {})",
            links.saturating_sub(1)
        )));
    }
    if kind == RecordKind::Link
        && data
            .first()
            .and_then(|&c| LinkState::from_code(c))
            .is_none()
    {
        return Err(bad("link record without a known state".into()));
    }
    Ok((
        Record {
            t_us,
            kind,
            link,
            data: data.to_vec(),
        },
        p + len + 4,
    ))
}
