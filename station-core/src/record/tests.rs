use super::format::put_varint;
use super::*;

/// A recording of another schema is said to be one (its undecodable frames explained);
/// this station's own, or one naming none, is not; a hostile fingerprint reaches the
/// terminal without its control characters.
#[test]
fn a_recording_of_another_message_schema_is_flagged() {
    let now = Meta::now("p", 115_200);
    assert_eq!(now.schema_warning(), None);
    assert_eq!(Meta::default().schema_warning(), None);
    let old = Meta {
        fingerprint: "2104a2c0f39dd1a0\x1b[2J".into(),
        ..now
    };
    let w = old.schema_warning().expect("a warning");
    assert!(w.contains("2104a2c0f39dd1a0"), "{w}");
    assert!(
        w.contains(&crate::link::machine::hex(&protocol::FINGERPRINT)),
        "{w}"
    );
    assert!(!w.contains('\x1b'), "{w:?}");
}

fn sample() -> Vec<u8> {
    let mut b = encode_header(&Meta {
        port: "memory".into(),
        ..Meta::default()
    });
    encode_record(&mut b, 0, RecordKind::Link, 0, &[1, b'm']);
    encode_record(&mut b, 10, RecordKind::ToRobot, 0, &[0, 1, 2]);
    encode_record(&mut b, 300, RecordKind::FromRobot, 0, &[5; 200]);
    encode_record(&mut b, 301, RecordKind::End, 0, b"done");
    b
}

#[test]
fn a_record_has_the_documented_bytes() {
    let mut b = Vec::new();
    encode_record(&mut b, 300, RecordKind::ToRobot, 0, &[0xaa, 0x00]);
    let crc = protocol::crc32c(&[0xac, 0x02, 0x01, 0x00, 0x02, 0xaa, 0x00]).to_le_bytes();
    let mut want = vec![0xac, 0x02, 0x01, 0x00, 0x02, 0xaa, 0x00];
    want.extend_from_slice(&crc);
    assert_eq!(b, want);
}

#[test]
fn the_header_starts_with_magic_and_version() {
    let h = encode_header(&Meta::default());
    assert_eq!(&h[..8], b"\x89STREC\r\n");
    assert_eq!(&h[8..12], &[2, 0, 0, 0]);
    let (header, at) = parse_header(&h).unwrap();
    assert_eq!(header.version, 2);
    assert_eq!(header.meta.links, vec![String::new()], "one link, the port");
    assert_eq!(at, h.len());
}

#[test]
fn a_whole_recording_reads_back() {
    let r = Recording::parse_strict(&sample()).unwrap();
    assert_eq!(r.records.len(), 4);
    assert_eq!(r.end.as_deref(), Some("done"));
    assert_eq!(r.meta.port, "memory");
    assert_eq!(r.duration_us(), 301);
    assert_eq!(
        r.records[0].link(),
        Some((LinkState::Handshaking, "m".into()))
    );
}

#[test]
fn every_truncation_reads_up_to_the_last_whole_record() {
    let full = sample();
    let (_, first) = parse_header(&full).unwrap();
    for cut in first..full.len() {
        let r = Recording::parse(&full[..cut]).unwrap();
        let whole = r.records.len();
        if let Some(e) = &r.damage {
            assert!(matches!(e, ReadError::Truncated { .. }), "{cut}: {e}");
        }
        assert!(whole < 4, "{cut}");
    }
    for cut in 0..first {
        assert!(Recording::parse(&full[..cut]).is_err(), "{cut}");
    }
}

#[test]
fn a_flipped_bit_is_found_at_its_record() {
    let full = sample();
    let (_, first) = parse_header(&full).unwrap();
    for i in first..full.len() {
        for bit in 0..8 {
            let mut b = full.clone();
            b[i] ^= 1 << bit;
            let r = Recording::parse(&b).unwrap();
            let e = r.damage.expect("damage found");
            assert!(e.offset() as usize <= i, "{i}.{bit}: {e}");
            assert!(r.records.len() < 4);
        }
    }
}

#[test]
fn bad_headers_are_named() {
    assert_eq!(Recording::parse(b"hello"), Err(ReadError::NotARecording));
    assert_eq!(Recording::parse(b""), Err(ReadError::NotARecording));
    let mut v3 = sample();
    v3[8] = 3;
    assert_eq!(
        Recording::parse(&v3),
        Err(ReadError::UnsupportedVersion { version: 3 })
    );
    let mut v0 = sample();
    v0[8] = 0;
    assert_eq!(
        Recording::parse(&v0),
        Err(ReadError::UnsupportedVersion { version: 0 })
    );
    let mut meta = sample();
    meta[HEADER_FIXED] ^= 0x20;
    assert!(matches!(
        Recording::parse(&meta),
        Err(ReadError::BadHeader { .. })
    ));
}

#[test]
fn the_record_crc_is_the_protocols_crc32c() {
    let bytes: Vec<u8> = (0..1000u32).map(|i| (i * 7 + i / 13) as u8).collect();
    for n in [0, 1, 15, 16, 17, 100, 1000] {
        assert_eq!(
            record_crc(&bytes[..n]),
            protocol::crc32c(&bytes[..n]),
            "{n}"
        );
    }
}

#[test]
fn unknown_kinds_are_kept_for_consumers_to_skip() {
    let mut b = encode_header(&Meta::default());
    encode_record(&mut b, 5, RecordKind::Unknown(200), 0, b"future");
    let r = Recording::parse_strict(&b).unwrap();
    assert_eq!(r.records[0].kind, RecordKind::Unknown(200));
}

/// A station log record (kind 4) reads back in a version 2 file: the format version is
/// unchanged, since a reader that predates the kind skips it as reserved.
#[test]
fn a_station_log_record_reads_back() {
    let line = StationLine {
        level: protocol::LogLevel::Error,
        source: LogSource::Command,
        text: "refused: go-to (9.00, 0.50): out of the arena".into(),
    };
    let mut b = encode_header(&Meta::default());
    encode_record(&mut b, 5, RecordKind::StationLog, 0, &line.encode());
    let r = Recording::parse_strict(&b).unwrap();
    assert_eq!(r.version, VERSION);
    assert_eq!(r.records[0].kind, RecordKind::StationLog);
    assert_eq!(r.records[0].data[..2], [3, 1], "level, then subject");
    assert_eq!(r.records[0].station_log(), Some(line));
    assert_eq!(RecordKind::from_code(4), RecordKind::StationLog);
}

#[test]
fn station_log_lines_read_leniently_and_are_cut_at_a_character() {
    assert_eq!(
        StationLine::decode(&[9, 77, b'x']),
        Some(StationLine {
            level: protocol::LogLevel::Info,
            source: LogSource::Station,
            text: "x".into()
        }),
        "an unknown level is info, an unknown subject the station's"
    );
    assert_eq!(StationLine::decode(&[1]), None);
    let line = StationLine {
        level: protocol::LogLevel::Info,
        source: LogSource::Link,
        text: "€".repeat(MAX_STATION_TEXT),
    };
    let data = line.encode();
    assert!(data.len() <= 2 + MAX_STATION_TEXT);
    let text = std::str::from_utf8(&data[2..]).unwrap();
    assert_eq!(text.len(), MAX_STATION_TEXT / 3 * 3);
}

#[test]
fn overlong_varints_and_huge_lengths_are_refused() {
    let mut b = encode_header(&Meta::default());
    let at = b.len();
    b.extend_from_slice(&[0xff; 11]);
    let r = Recording::parse(&b).unwrap();
    assert!(matches!(r.damage, Some(ReadError::BadRecord { offset, .. }) if offset == at as u64));
    let mut b = encode_header(&Meta::default());
    b.extend_from_slice(&[0x00, 0x00, 0xff, 0xff, 0xff, 0x7f]);
    let r = Recording::parse(&b).unwrap();
    assert!(matches!(r.damage, Some(ReadError::BadRecord { .. })));
}

#[test]
fn a_time_beyond_a_year_is_damage_at_its_record() {
    for t in [MAX_T_US + 1, u64::MAX] {
        let mut b = encode_header(&Meta::default());
        encode_record(&mut b, 0, RecordKind::Link, 0, &[1, b'm']);
        encode_record(&mut b, MAX_T_US, RecordKind::FromRobot, 0, &[0]);
        let at = b.len() as u64;
        encode_record(&mut b, t, RecordKind::FromRobot, 0, &[0]);
        let r = Recording::parse(&b).unwrap();
        let e = r.damage.clone().expect("refused");
        assert_eq!(e.offset(), at);
        assert!(e.to_string().contains("more than a year"), "{e}");
        assert_eq!(r.duration_us(), MAX_T_US, "read up to there");
    }
}

#[test]
fn records_after_the_end_are_damage() {
    let mut b = sample();
    encode_record(&mut b, 400, RecordKind::FromRobot, 0, &[1]);
    let r = Recording::parse(&b).unwrap();
    assert!(matches!(r.damage, Some(ReadError::BadRecord { .. })));
    assert_eq!(r.records.len(), 4);
}

/// A version 1 header and record, as the station wrote them before links existed.
fn v1_header(meta: &Meta) -> Vec<u8> {
    let mut h = encode_header(meta);
    // The same header with version 1 and the meta without `links`, CRC recomputed.
    let json = serde_json::to_vec(meta).unwrap();
    h.truncate(8);
    h.extend_from_slice(&1u16.to_le_bytes());
    h.extend_from_slice(&0u16.to_le_bytes());
    h.extend_from_slice(&(json.len() as u32).to_le_bytes());
    h.extend_from_slice(&json);
    let crc = protocol::crc32c(&h);
    h.extend_from_slice(&crc.to_le_bytes());
    h
}

fn v1_record(out: &mut Vec<u8>, t_us: u64, kind: RecordKind, data: &[u8]) {
    let start = out.len();
    put_varint(out, t_us);
    out.push(kind.code());
    put_varint(out, data.len() as u64);
    out.extend_from_slice(data);
    let crc = protocol::crc32c(&out[start..]);
    out.extend_from_slice(&crc.to_le_bytes());
}

#[test]
fn a_version_1_file_reads_as_link_0() {
    let mut b = v1_header(&Meta {
        port: "/dev/ttyUSB0".into(),
        ..Meta::default()
    });
    v1_record(&mut b, 0, RecordKind::Link, &[1, b'm']);
    v1_record(&mut b, 7, RecordKind::FromRobot, &[5; 20]);
    v1_record(&mut b, 9, RecordKind::End, b"done");
    let r = Recording::parse_strict(&b).unwrap();
    assert_eq!(r.version, 1);
    assert_eq!(r.link_count(), 1);
    assert_eq!(r.meta.link_ports(), vec!["/dev/ttyUSB0".to_string()]);
    assert!(r.records.iter().all(|x| x.link == 0));
    assert_eq!(r.link(0).records, r.records);
}

fn two_links() -> Vec<u8> {
    let mut b = encode_header(&Meta {
        links: vec!["/tmp/robot1".into(), "/tmp/robot2".into()],
        ..Meta::default()
    });
    encode_record(&mut b, 0, RecordKind::Link, 0, &[1, b'a']);
    encode_record(&mut b, 1, RecordKind::Link, 1, &[1, b'b']);
    encode_record(&mut b, 5, RecordKind::FromRobot, 1, &[2; 30]);
    encode_record(&mut b, 6, RecordKind::FromRobot, 0, &[3; 30]);
    encode_record(&mut b, 9, RecordKind::End, 0, b"done");
    b
}

#[test]
fn links_split_into_recordings_of_their_own() {
    let r = Recording::parse_strict(&two_links()).unwrap();
    assert_eq!(r.link_count(), 2);
    let [a, b] = <[Recording; 2]>::try_from(r.links()).unwrap();
    assert_eq!(a.meta.port, "/tmp/robot1");
    assert_eq!(b.meta.port, "/tmp/robot2");
    let data = |x: &Recording| -> Vec<u8> {
        x.records
            .iter()
            .filter(|r| r.kind == RecordKind::FromRobot)
            .flat_map(|r| r.data.clone())
            .collect()
    };
    assert_eq!(data(&a), vec![3; 30]);
    assert_eq!(data(&b), vec![2; 30]);
    // The end record ends every link.
    assert_eq!(a.end.as_deref(), Some("done"));
    assert_eq!(b.records.last().map(|r| r.kind), Some(RecordKind::End));
}

#[test]
fn a_link_id_the_header_does_not_name_is_damage_at_its_record() {
    let mut b = encode_header(&Meta {
        links: vec!["a".into(), "b".into()],
        ..Meta::default()
    });
    encode_record(&mut b, 0, RecordKind::Link, 1, &[1, b'b']);
    let at = b.len() as u64;
    encode_record(&mut b, 3, RecordKind::FromRobot, 2, &[0]);
    let r = Recording::parse(&b).unwrap();
    let e = r.damage.expect("refused");
    assert_eq!(e.offset(), at);
    assert!(
        e.to_string()
            .contains("link id 2, but the header names 2 link(s)"),
        "{e}"
    );
    assert_eq!(r.records.len(), 1);
}

#[test]
fn a_version_2_header_without_links_is_refused() {
    let mut meta = Meta::default();
    meta.links.clear();
    let mut h = v1_header(&meta);
    h[8] = 2;
    let n = h.len();
    let crc = protocol::crc32c(&h[..n - 4]);
    h[n - 4..].copy_from_slice(&crc.to_le_bytes());
    let e = Recording::parse(&h).unwrap_err();
    assert!(matches!(e, ReadError::BadHeader { offset: 16, .. }), "{e}");
    assert!(e.to_string().contains("names 0 links"), "{e}");
}

#[test]
fn every_truncation_of_a_two_link_file_is_named_at_its_record() {
    let full = two_links();
    let (_, first) = parse_header(&full).unwrap();
    for cut in first + 1..full.len() {
        let r = Recording::parse(&full[..cut]).unwrap();
        // A cut at a record boundary reads cleanly (without an end record).
        let Some(e) = r.damage else { continue };
        let ReadError::Truncated { offset } = e else {
            panic!("{cut}: {e}");
        };
        assert!(offset as usize <= cut, "{cut}");
        let (_, next) = parse_record(&full, offset as usize, 2, 2).unwrap();
        assert!(next > cut, "{cut}: the record at {offset} is the one cut");
    }
}
