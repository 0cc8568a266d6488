//! The handshake and its renewal, and what the link does with refusals and unverifiable
//! frames (PROTOCOL.md §4, §13): `LinkMachine`'s session half, apart from its frame and
//! command half in `machine`.

use super::*;

impl LinkMachine {
    pub(super) fn start_handshake(&mut self, now_ms: u64) {
        self.renewal_since_ms = None;
        let session = self.next_nonce();
        self.robot_clock.reset();
        self.line_phase.reset();
        self.stats.robot_seq.reset();
        self.stats.truth_seq.reset();
        // The robot signs on from our Hello's timestamp (PROTOCOL.md §13), so nothing it
        // signed before this Hello is current: a replay of an old session is stale.
        let hello_ts = self.auth.next_timestamp(self.clock(now_ms));
        self.auth.reset_replay(hello_ts);
        self.send_hello(now_ms, session);
        self.state = State::Handshaking {
            session,
            next_hello_ms: now_ms + HELLO_RETRY_MS,
        };
        self.set_connection(Connection::Handshaking {
            port: self.port.clone(),
        });
    }

    /// Handshakes again within a live session, once nothing is in flight, before the counter
    /// could reach a number the robot remembers a reply for (PROTOCOL.md §7). Returns whether
    /// new commands must wait.
    pub(super) fn renew_if_due(&mut self, now_ms: u64) -> bool {
        if self.session_frames < RENEW_AFTER_FRAMES {
            return false;
        }
        if self.commands.in_flight() == 0 {
            self.stats.renewals = self.stats.renewals.saturating_add(1);
            self.start_handshake(now_ms);
            self.renewal_since_ms = Some(now_ms);
        }
        true
    }

    pub(super) fn send_hello(&mut self, now_ms: u64, session: u32) {
        let station = self.cfg.station.clone();
        let hello = Hello {
            fingerprint: FINGERPRINT,
            protocol: PROTOCOL_VERSION,
            session,
            station: &station,
        };
        // Until a reply names the robot, the robot's frames of this session are not ours:
        // only the reply and a refusal of this Hello verify (PROTOCOL.md §13).
        self.auth.bind(Binding::new(session, ANY_ROBOT));
        self.send(now_ms, &Message::Hello(hello));
    }

    /// A frame that passed the CRC but not authentication: counted (the stats show it) and
    /// dropped. Before a session, a key on one side only or a different key is what it means,
    /// and the user is told so instead of waiting for a timeout.
    /// `refusal`: the frame decodes as the robot's `HandshakeRefused`.
    pub(super) fn on_auth_error(&mut self, e: AuthError, refusal: bool) {
        if self.connected() {
            return;
        }
        let why = match e {
            // Only the robot's refusal of a Hello says which key it has: it is bound to no
            // session, so with our key it verifies. Any other frame that does not verify may
            // be the robot's last session with another station, still in the port (bound to
            // that session), or a frame relayed from another robot: counted only.
            AuthError::BadSignature { .. } if !refusal => return,
            AuthError::BadSignature { .. } => {
                "the robot's frames do not verify with this station's key (the robot has \
                 another key)"
            }
            AuthError::UnexpectedSignature { .. } => {
                "the robot signs its frames (it has a key) but this station has no key"
            }
            AuthError::Unsigned => {
                "the robot does not sign its frames (it has no key) but this station has one; \
                 give both the same key or neither"
            }
            // Replays, reflections and stale frames are an attacker's or the past's, not a
            // misconfiguration: counted only.
            AuthError::StaleTimestamp { .. }
            | AuthError::WrongDirection { .. }
            | AuthError::TooManyLinks { .. } => return,
        };
        self.refuse_auth(why);
    }

    /// The robot's `Event HandshakeRefused` with a negative value: it could not authenticate
    /// our `Hello` (PROTOCOL.md §13).
    ///
    /// The refusal names no session, so it is believed only if it describes what we sent: a
    /// refusal of signed frames reaching a station that signs nothing (or of unsigned ones
    /// reaching one that signs) answered another station's Hello, and was left in the port
    /// when that station exited. A stale refusal that does fit ours says what ours would
    /// hear: the robot's key setup is the same for both. (A keyed station never sees an
    /// old signed refusal: it is below our Hello's timestamp, `StaleTimestamp`.)
    pub(super) fn on_robot_auth_refusal(&mut self, code: i32) {
        let keyed = self.auth.keyed();
        let why = match code {
            -1 if !keyed => "the robot has a key and refused our unsigned frames",
            -2 if keyed => "the robot refused our signature (it has another key)",
            -4 if keyed => "the robot has no key and refused our signed frames",
            // -3 stale: our next Hello's timestamp follows the robot's, so it heals by itself.
            _ => return,
        };
        self.refuse_auth(why);
    }

    pub(super) fn refuse_auth(&mut self, why: &str) {
        let session = match self.state {
            State::Handshaking { session, .. } | State::Refused { session, .. } => session,
            _ => self.next_nonce(),
        };
        let message = format!("link authentication failed: {why}; check --key-file");
        // Retried at the Hello pace: a robot restarted with the right key connects at once.
        self.state = State::Refused {
            session,
            next_hello_ms: self.last_tx_ms + HELLO_RETRY_MS,
        };
        self.set_connection(Connection::Refused { message });
    }

    pub(super) fn on_hello_reply(&mut self, now_ms: u64, r: OwnedHelloReply) {
        let expected = match self.state {
            State::Handshaking { session, .. } | State::Refused { session, .. } => session,
            // A late duplicate of the reply that opened this session, or noise: ignore.
            State::Connected { .. } | State::Closed => return,
        };
        if r.session != expected {
            return;
        }
        if r.accepted && r.fingerprint == FINGERPRINT && r.protocol == PROTOCOL_VERSION {
            self.stats.handshakes = self.stats.handshakes.saturating_add(1);
            // From now on both directions sign for this session and this robot: a frame of
            // another robot sharing the key, relayed onto this line, does not verify.
            self.auth.bind(Binding::new(r.session, r.robot_id));
            self.state = State::Connected {
                session: r.session,
                since_ms: now_ms,
            };
            self.session_frames = 0;
            self.renewal_since_ms = None;
            self.set_connection(Connection::Connected(PeerInfo {
                session: r.session,
                firmware: r.firmware,
                firmware_version: r.firmware_version,
                profile: r.profile,
                capabilities: r.capabilities,
                map_capacity: r.map_capacity,
                telemetry_hz: r.telemetry_hz,
                failsafe_ms: r.failsafe_ms,
                robot_id: r.robot_id,
            }));
            // Commands that waited through a renewal go out in the new session.
            self.pump(now_ms);
        } else {
            let message = format!(
                "robot firmware {} {} has schema {} (protocol {}); this station has schema {} \
                 (protocol {}): rebuild one of them",
                r.firmware,
                r.firmware_version,
                hex(&r.fingerprint),
                r.protocol,
                hex(&FINGERPRINT),
                PROTOCOL_VERSION
            );
            self.refuse(now_ms, message);
        }
    }

    pub(super) fn refuse(&mut self, now_ms: u64, message: String) {
        if self.renewal_since_ms.take().is_some() {
            self.fail_all(CommandFailure::LinkLost);
        }
        let session = match self.state {
            State::Handshaking { session, .. } | State::Refused { session, .. } => session,
            _ => self.next_nonce(),
        };
        self.state = State::Refused {
            session,
            next_hello_ms: now_ms + REFUSED_RETRY_MS,
        };
        self.set_connection(Connection::Refused { message });
    }

    pub(super) fn next_nonce(&mut self) -> u32 {
        // splitmix64: distinct nonces from one seed.
        self.rng = self.rng.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.rng;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        (z ^ (z >> 31)) as u32
    }
}
