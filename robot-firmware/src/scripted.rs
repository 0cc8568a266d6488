//! A scripted `Hal` for host tests and benchmarks: sensor values and received bytes are set by
//! the test, motor commands and sent bytes are recorded. No world, no physics: the emulator is
//! the real simulation. Fixed-size buffers, so it is `no_std` like the rest of the crate.

use heapless::Deque;

use crate::hal::{BeaconReading, GripperCommand, GripperState, Hal, MotorCommand, CAMERA_PIXELS};

/// Bytes a scripted port holds in each direction.
pub const SCRIPTED_PORT: usize = 4096;

/// The test double.
pub struct ScriptedHal {
    pub now_us: u64,
    pub motors: MotorCommand,
    /// Every motor command ever set that was not a stop, counted.
    pub motor_moves: u32,
    pub encoders: Option<[i32; 2]>,
    pub ir: [u16; 8],
    pub ambient: [u16; 8],
    pub compass: Option<f32>,
    pub ground: bool,
    pub line: bool,
    pub beacon: Option<BeaconReading>,
    pub battery_mv: u16,
    /// The gripper's report; `None` = no gripper.
    pub gripper: Option<GripperState>,
    /// The last gripper command set.
    pub gripper_cmd: GripperCommand,
    /// The camera line; `None` = no camera.
    pub camera: Option<[u8; CAMERA_PIXELS]>,
    /// ALICE's whisker bits; `None` = no whiskers.
    pub whiskers: Option<u32>,
    /// ALICE's photoresistors; `None` = none.
    pub photoresistors: Option<[u8; crate::alice::SENSORS]>,
    /// Bytes waiting for the robot to read.
    pub rx: Deque<u8, SCRIPTED_PORT>,
    /// Bytes the robot sent.
    pub tx: Deque<u8, SCRIPTED_PORT>,
    /// Largest write the transmitter accepts at once (models a small UART buffer).
    pub tx_chunk: usize,
}

impl Default for ScriptedHal {
    fn default() -> Self {
        ScriptedHal {
            now_us: 0,
            motors: MotorCommand::STOP,
            motor_moves: 0,
            encoders: None,
            ir: [0; 8],
            ambient: [0; 8],
            compass: None,
            ground: false,
            line: false,
            beacon: None,
            battery_mv: 0,
            gripper: None,
            gripper_cmd: GripperCommand::default(),
            camera: None,
            whiskers: None,
            photoresistors: None,
            rx: Deque::new(),
            tx: Deque::new(),
            tx_chunk: usize::MAX,
        }
    }
}

impl ScriptedHal {
    /// Queues bytes for the robot to read; returns how many fitted.
    pub fn push_rx(&mut self, bytes: &[u8]) -> usize {
        bytes
            .iter()
            .take_while(|b| self.rx.push_back(**b).is_ok())
            .count()
    }

    /// Takes up to `out.len()` bytes the robot sent.
    pub fn take_tx(&mut self, out: &mut [u8]) -> usize {
        drain_into(&mut self.tx, out)
    }
}

/// Moves bytes from the front of `q` into `out`; returns how many.
fn drain_into(q: &mut Deque<u8, SCRIPTED_PORT>, out: &mut [u8]) -> usize {
    let mut n = 0;
    for slot in out.iter_mut() {
        match q.pop_front() {
            Some(b) => {
                *slot = b;
                n += 1;
            }
            None => break,
        }
    }
    n
}

impl Hal for ScriptedHal {
    fn now_us(&mut self) -> u64 {
        self.now_us
    }

    fn set_motors(&mut self, cmd: MotorCommand) {
        if cmd != MotorCommand::STOP {
            self.motor_moves = self.motor_moves.saturating_add(1);
        }
        self.motors = cmd;
    }

    fn encoders(&mut self) -> Option<[i32; 2]> {
        self.encoders
    }

    fn ir(&mut self) -> [u16; 8] {
        self.ir
    }

    fn ambient(&mut self) -> [u16; 8] {
        self.ambient
    }

    fn compass(&mut self) -> Option<f32> {
        self.compass
    }

    fn ground(&mut self) -> bool {
        self.ground
    }

    fn line(&mut self) -> bool {
        self.line
    }

    fn beacon(&mut self) -> Option<BeaconReading> {
        self.beacon
    }

    fn battery_mv(&mut self) -> u16 {
        self.battery_mv
    }

    fn gripper(&mut self) -> Option<GripperState> {
        self.gripper
    }

    fn set_gripper(&mut self, cmd: GripperCommand) {
        self.gripper_cmd = cmd;
    }

    fn camera(&mut self, image: &mut [u8; CAMERA_PIXELS]) -> bool {
        if let Some(line) = self.camera {
            *image = line;
        }
        self.camera.is_some()
    }

    fn whiskers(&mut self) -> Option<u32> {
        self.whiskers
    }

    fn photoresistors(&mut self) -> Option<[u8; crate::alice::SENSORS]> {
        self.photoresistors
    }

    fn serial_read(&mut self, buf: &mut [u8]) -> usize {
        drain_into(&mut self.rx, buf)
    }

    fn serial_write(&mut self, bytes: &[u8]) -> usize {
        bytes
            .iter()
            .take(self.tx_chunk)
            .take_while(|b| self.tx.push_back(**b).is_ok())
            .count()
    }
}
