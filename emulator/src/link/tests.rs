use super::*;

/// The serving loop used to wake every millisecond whatever happened; now an idle wire
/// lets it sleep until the robot's next cycle (at most `IDLE_LOOK_US`), and bytes on the
/// wire bring back the 1 ms steps that move them (each due as the clock reaches its start).
#[test]
fn an_idle_wire_lets_the_loop_sleep_and_bytes_on_it_bring_back_1_ms_steps() {
    let arena = crate::builtin::micro_rato_99(&crate::arena::LoadOptions::default()).unwrap();
    let cfg = crate::sim::SimConfig::new(&robot_firmware::MICRO_RATO);
    let mut sim = crate::sim::Sim::new(arena, cfg).unwrap();
    // No station: the robot sends nothing; between two cycles the wire is idle.
    let mut idle_dues = 0;
    for _ in 0..200 {
        sim.step();
        let due = sim.next_due_us() - sim.now_us();
        assert!((0..=IDLE_LOOK_US).contains(&due), "{due} us");
        idle_dues += usize::from(due >= 1000);
    }
    assert!(
        idle_dues > 100,
        "only {idle_dues} of 200 looks were 1 ms or more ahead"
    );
    // A station's bytes on their way in: the next step is due at once.
    Device::push_inbound(&mut sim, &[0u8; 40]);
    assert_eq!(sim.next_due_us(), sim.now_us());
}

/// Issue 15: the robot's answer to a command reaches the station as its bytes allow, not
/// on millisecond boundaries. The loop used to step a millisecond only once the clock had
/// passed its end (the robot acting up to 1 ms late) and to hand over bytes only at those
/// ends; then the robot still read a command only at the next step's start (0.5 ms late on
/// average). Now the robot acts the moment a command's last bit arrives (`Sim::step`'s
/// passes at frame ends). In simulated time, driven as `serve` drives it (its
/// `step_until`, `next_look_us` and the exchange's clock), for commands arriving at every
/// tenth of a millisecond: never faster than the wire, and no slower but for the line's
/// clock (each frame starts at a whole bit: up to a bit each), or, for a command completing
/// inside the step the loop had already run when its bytes came, until that step's end.
#[test]
fn a_command_is_answered_as_soon_as_its_bytes_allow() {
    use protocol::{encode, Command, Message, MAX_FRAME};
    let arena = crate::builtin::micro_rato_99(&crate::arena::LoadOptions::default()).unwrap();
    let cfg = crate::sim::SimConfig::new(&robot_firmware::MICRO_RATO);
    let mut sim = crate::sim::Sim::new(arena, cfg).unwrap();
    let baud = f64::from(sim.uart().baud());
    let byte_us = |n: usize| n as f64 * 10.0 * 1e6 / baud;
    let bit_us = 1e6 / baud;
    let mut frame = [0u8; MAX_FRAME];
    let mut late_ones = 0;
    for (i, offset_us) in (0..10u64).map(|i| (i, 100 * i + 37)).collect::<Vec<_>>() {
        // No session: the robot is quiet, and answers Nack NoHandshake (a reply all the
        // same, as long as an Ack).
        let n = encode(i as u16, &Message::Command(Command::Stop), &mut frame).unwrap();
        let at = 20_000 * (i + 1) + offset_us;
        step_until(&mut sim, at, &mut |_| {});
        Device::push_inbound_at(&mut sim, frame.get(..n).unwrap(), at);
        let command_end = sim.uart().next_inbound_frame_end_us().unwrap();
        // The step under way has run: a command completing in it is read at its end.
        let late = sim.now_us().saturating_sub(command_end) as f64;
        late_ones += usize::from(late > 0.0);
        let mut out = Vec::new();
        let mut t = at;
        let mut looks = 0;
        while !out.contains(&0) {
            t = next_look_us(&sim).max(t);
            step_until(&mut sim, t, &mut |_| {});
            Device::take_outbound_until(&mut sim, t, &mut out);
            looks += 1;
            assert!(
                t < at + 10_000 && looks < 1000,
                "no answer 10 ms after a command at {at} us ({looks} looks)"
            );
        }
        let wire = byte_us(n) + byte_us(out.len());
        let took = (t - at) as f64;
        assert!(
            took >= wire,
            "answered in {took} us, faster than its {wire:.0} us of bytes"
        );
        assert!(
            took <= wire + late + 2.0 * bit_us + 2.0,
            "answered in {took} us: more than its {wire:.0} us of bytes (+{late} us)"
        );
    }
    // A Stop takes 0.95 ms: only the one arriving 37 us into its step completes in it.
    assert_eq!(late_ones, 1);
}

/// Bytes from the station end the loop's wait at once (it used to sleep its 1 ms out).
#[test]
fn bytes_from_the_station_end_the_wait() {
    let pty = Pty::open(None).unwrap();
    let slave = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(pty.slave_path())
        .unwrap();
    std::io::Write::write_all(&mut &slave, b"x").unwrap();
    let t0 = Instant::now();
    pty.wait_input(Duration::from_secs(20));
    assert!(
        t0.elapsed() < Duration::from_secs(20),
        "waited the timeout out"
    );
    drop(slave);
}

#[test]
fn key_files_are_read_whole_only_when_short() {
    let dir = std::env::temp_dir();
    let key = "00112233445566778899aabbccddeeff00112233445566778899aabbccddeeff";
    let ok = dir.join(format!("emu-key-ok-{}", std::process::id()));
    std::fs::write(&ok, format!("  {key}\n")).unwrap();
    private(&ok, 0o600);
    assert!(read_key_file(&ok).is_ok());
    let long = dir.join(format!("emu-key-long-{}", std::process::id()));
    std::fs::write(&long, format!("{key}{}", " ".repeat(5000))).unwrap();
    private(&long, 0o600);
    let e = read_key_file(&long).unwrap_err();
    assert!(
        e.contains("key files are limited to 4096 bytes") && e.contains("emu-key-long"),
        "{e}"
    );
    let _ = std::fs::remove_file(ok);
    let _ = std::fs::remove_file(long);
}

fn private(path: &Path, mode: u32) {
    use std::os::unix::fs::PermissionsExt as _;
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(mode)).unwrap();
}

#[test]
fn key_files_that_group_or_others_may_access_are_refused_with_the_mode_and_the_fix() {
    let key = "00112233445566778899aabbccddeeff00112233445566778899aabbccddeeff";
    let path = std::env::temp_dir().join(format!("emu-key-mode-{}", std::process::id()));
    std::fs::write(&path, key).unwrap();
    for mode in [0o644, 0o640, 0o604, 0o620, 0o666] {
        private(&path, mode);
        let e = read_key_file(&path).unwrap_err();
        assert!(
            e.contains(&format!("(mode {mode:04o})"))
                && e.contains(&format!("chmod 600 {}", path.display())),
            "{e}"
        );
    }
    for mode in [0o600, 0o400] {
        private(&path, mode);
        assert!(read_key_file(&path).is_ok(), "{mode:o}");
    }
    let _ = std::fs::remove_file(path);
}
