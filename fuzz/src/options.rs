//! How a `link_input` run starts and what the board does besides the link: the options the
//! first bytes of a fuzz input choose ([`Options`]), read by [`crate::vehicle::Vehicle`].

/// How a run starts and what the board does besides the link: the first
/// [`Options::HEADER_LEN`] bytes of a `link_input` fuzz input.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Options {
    /// The store holds a payload description (rect-sim1's) at the start.
    pub payload_stored: bool,
    /// The store holds the signing key [`SEED_KEY`](crate::vehicle::SEED_KEY) at the start: signing is on.
    pub key_stored: bool,
    /// The board's IMU driver steps the control task: [`Self::ticks`] steps after each
    /// frame, [`TICK_US`](crate::vehicle::TICK_US) apart on the board's clock, at most [`MAX_DRIVER_STEPS`](crate::vehicle::MAX_DRIVER_STEPS) in a run
    /// (HIL_SENSOR frames step it in any case).
    pub imu_driver: bool,
    /// With the IMU driver: a motion-capture fix at rest comes with each of its steps.
    pub mocap: bool,
    /// The link may set the signing key (USB, or QEMU's board); not on TELEM1.
    pub key_setup_allowed: bool,
    /// The IMU driver reports a fault (from frame [`Self::faults_from`] on).
    pub imu_fault: bool,
    /// Control steps the IMU driver takes after each frame.
    pub ticks: u8,
    /// Robots whose steppers report a stall (bit j: robot j), from frame
    /// [`Self::faults_from`] on.
    pub stalled_robots: u8,
    /// The frame from which the drivers report their faults.
    pub faults_from: u8,
    /// The stream's frames get their checksums recomputed before they arrive
    /// ([`fix_checksums`]), so that a mutated frame reaches the services instead of being
    /// dropped by the parser for its checksum.
    pub fix_checksums: bool,
    /// An uploaded payload description gets its CRC-32 (its last four bytes) recomputed when
    /// its upload closes, as if the ground station had written a well-formed file of those
    /// contents: mutated descriptions reach the checks and, passing them, the mission.
    pub fix_payload_checksum: bool,
}

impl Options {
    /// Bytes of the header.
    pub const HEADER_LEN: usize = 4;

    /// The options of a header: flags (bit 0 payload stored, 1 key stored, 2 IMU driver,
    /// 3 motion capture, 4 key setup allowed, 5 IMU fault, 6 fix checksums, 7 fix the
    /// payload's checksum), ticks, stalled robots, the frame the faults start at.
    pub fn from_header(h: [u8; Self::HEADER_LEN]) -> Self {
        let [flags, ticks, stalled_robots, faults_from] = h;
        Self {
            payload_stored: flags & 1 != 0,
            key_stored: flags & 2 != 0,
            imu_driver: flags & 4 != 0,
            mocap: flags & 8 != 0,
            key_setup_allowed: flags & 16 != 0,
            imu_fault: flags & 32 != 0,
            fix_checksums: flags & 64 != 0,
            fix_payload_checksum: flags & 128 != 0,
            ticks,
            stalled_robots,
            faults_from,
        }
    }

    /// The header of these options.
    pub fn header(&self) -> [u8; Self::HEADER_LEN] {
        let flags = u8::from(self.payload_stored)
            | u8::from(self.key_stored) << 1
            | u8::from(self.imu_driver) << 2
            | u8::from(self.mocap) << 3
            | u8::from(self.key_setup_allowed) << 4
            | u8::from(self.imu_fault) << 5
            | u8::from(self.fix_checksums) << 6
            | u8::from(self.fix_payload_checksum) << 7;
        [flags, self.ticks, self.stalled_robots, self.faults_from]
    }
}
