//! The recording reader (`station replay`, `station export`) on arbitrary bytes, then the
//! replay's path for what it accepts: the recorded robot bytes through the station's own link
//! machine. Invariants: no panic; a strict parse succeeds exactly when the lenient one finds
//! no damage; record times never decrease; nothing follows an End record; a reported damage
//! offset lies inside the file.
#![no_main]

use libfuzzer_sys::fuzz_target;
use station::link::{LinkMachine, MachineConfig};
use station::record::{RecordKind, Recording};

fuzz_target!(|data: &[u8]| {
    let lenient = Recording::parse(data);
    let strict = Recording::parse_strict(data);
    let Ok(rec) = lenient else {
        assert!(strict.is_err(), "strict accepted what lenient refused");
        return;
    };
    assert_eq!(strict.is_ok(), rec.damage.is_none());
    if let Some(e) = &rec.damage {
        assert!(e.offset() <= data.len() as u64, "damage past the end: {e}");
    }
    let mut last = 0;
    for (i, r) in rec.records.iter().enumerate() {
        assert!(r.t_us >= last, "time went back");
        last = r.t_us;
        if r.kind == RecordKind::End {
            assert_eq!(i + 1, rec.records.len(), "a record after End");
        }
        assert!(usize::from(r.link) < rec.link_count(), "a link the header does not name");
        let _ = r.link();
    }
    let mut link = LinkMachine::new(MachineConfig {
        station: "fuzz".into(),
        nonce_seed: 1,
    });
    link.port_opened(0, "replay");
    for r in &rec.records {
        let ms = r.t_us / 1000;
        if r.kind == RecordKind::FromRobot {
            link.receive(ms, &r.data);
        }
        link.poll(ms);
        let _ = link.take_events();
        let _ = link.take_output();
    }
});
