//! The HIL link's Ethernet framing (docs/firmware.md#hil-transports): MAVLink bytes carried in
//! raw Ethernet frames between the firmware on QEMU's mps2-an500 (its LAN9118 controller) and
//! the plant, which QEMU's `socket` network back end hands each frame as one UDP datagram.
//!
//! A frame is the Ethernet header (destination, source, EtherType [`ETHERTYPE`]), then the
//! number of MAVLink bytes that follow (16 bits, little-endian), then those bytes: whole
//! MAVLink frames, as a serial link would carry them, so the same parser reads either link.
//! The length field makes the frame independent of what the wire adds after it (the
//! minimum-size padding of real Ethernet, the controller's CRC word).

/// EtherType of the HIL frames: IEEE 802's "local experimental EtherType 1", for protocols
/// that never leave a test set-up.
pub const ETHERTYPE: u16 = 0x88B5;
/// The firmware's (locally administered) MAC address.
pub const VEHICLE_MAC: [u8; 6] = [0x02, 0x48, 0x49, 0x4C, 0x00, 0x01];
/// The plant's (locally administered) MAC address.
pub const PLANT_MAC: [u8; 6] = [0x02, 0x48, 0x49, 0x4C, 0x00, 0xFE];
/// Bytes before the MAVLink bytes: Ethernet header (14) and the length (2).
pub const HEADER_LEN: usize = 16;
/// Largest Ethernet payload (the standard MTU).
pub const MTU: usize = 1500;
/// Most MAVLink bytes one frame carries.
pub const MAX_PAYLOAD: usize = MTU - 2;
/// Largest frame: header and [`MAX_PAYLOAD`].
pub const MAX_FRAME: usize = HEADER_LEN + MAX_PAYLOAD;

/// Why a received frame carries no MAVLink bytes for us.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameError {
    /// Shorter than the header.
    Short {
        /// Its length, bytes.
        len: usize,
    },
    /// Another protocol's frame.
    OtherProtocol {
        /// Its EtherType.
        ethertype: u16,
    },
    /// The length field says more bytes than the frame holds.
    Truncated {
        /// MAVLink bytes the length field announces.
        announced: usize,
        /// Bytes after the header.
        present: usize,
    },
}

impl core::fmt::Display for FrameError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Short { len } => write!(f, "an Ethernet frame of {len} bytes has no header"),
            Self::OtherProtocol { ethertype } => {
                write!(
                    f,
                    "an Ethernet frame of EtherType 0x{ethertype:04x} is not HIL's"
                )
            }
            Self::Truncated { announced, present } => write!(
                f,
                "an Ethernet frame announces {announced} MAVLink bytes but holds {present}"
            ),
        }
    }
}

/// The header of a frame from `source` to `destination` carrying `payload_len` MAVLink bytes
/// (at most [`MAX_PAYLOAD`]; more is cut to it).
pub fn header(destination: [u8; 6], source: [u8; 6], payload_len: usize) -> [u8; HEADER_LEN] {
    let len = payload_len.min(MAX_PAYLOAD) as u16;
    let mut h = [0u8; HEADER_LEN];
    h[0..6].copy_from_slice(&destination);
    h[6..12].copy_from_slice(&source);
    h[12..14].copy_from_slice(&ETHERTYPE.to_be_bytes());
    h[14..16].copy_from_slice(&len.to_le_bytes());
    h
}

/// The MAVLink bytes of a received frame (whatever follows them, padding or a CRC, ignored).
pub fn payload(frame: &[u8]) -> Result<&[u8], FrameError> {
    if frame.len() < HEADER_LEN {
        return Err(FrameError::Short { len: frame.len() });
    }
    let ethertype = u16::from_be_bytes([frame[12], frame[13]]);
    if ethertype != ETHERTYPE {
        return Err(FrameError::OtherProtocol { ethertype });
    }
    let announced = usize::from(u16::from_le_bytes([frame[14], frame[15]]));
    let rest = &frame[HEADER_LEN..];
    rest.get(..announced).ok_or(FrameError::Truncated {
        announced,
        present: rest.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    fn frame(bytes: &[u8]) -> Vec<u8> {
        let mut f = header(PLANT_MAC, VEHICLE_MAC, bytes.len()).to_vec();
        f.extend_from_slice(bytes);
        f
    }

    #[test]
    fn the_payload_comes_back_whatever_follows_it() {
        let bytes = [0xFD, 9, 0, 0, 7, 1, 1, 0, 0, 0];
        let mut f = frame(&bytes);
        assert_eq!(payload(&f), Ok(&bytes[..]));
        // Real Ethernet pads to 60 bytes, the LAN9118 appends its CRC word.
        f.resize(60, 0);
        f.extend_from_slice(&[0xDE, 0xAD, 0xBE, 0xEF]);
        assert_eq!(payload(&f), Ok(&bytes[..]));
    }

    #[test]
    fn the_header_names_both_ends_and_the_protocol() {
        let h = header(VEHICLE_MAC, PLANT_MAC, 300);
        assert_eq!(&h[0..6], &VEHICLE_MAC);
        assert_eq!(&h[6..12], &PLANT_MAC);
        assert_eq!(&h[12..14], &[0x88, 0xB5]);
        assert_eq!(u16::from_le_bytes([h[14], h[15]]), 300);
        // More than one frame can carry is cut to what one can.
        let h = header(VEHICLE_MAC, PLANT_MAC, 5000);
        assert_eq!(usize::from(u16::from_le_bytes([h[14], h[15]])), MAX_PAYLOAD);
    }

    #[test]
    fn foreign_short_and_truncated_frames_are_refused_with_the_reason() {
        assert_eq!(payload(&[0u8; 10]), Err(FrameError::Short { len: 10 }));
        let mut ipv4 = frame(&[1, 2, 3]);
        ipv4[12] = 0x08;
        ipv4[13] = 0x00;
        assert_eq!(
            payload(&ipv4),
            Err(FrameError::OtherProtocol { ethertype: 0x0800 })
        );
        let mut cut = frame(&[1, 2, 3, 4, 5]);
        cut.truncate(HEADER_LEN + 2);
        assert_eq!(
            payload(&cut),
            Err(FrameError::Truncated {
                announced: 5,
                present: 2
            })
        );
        let text = std::format!("{}", payload(&cut).unwrap_err());
        assert!(text.contains("announces 5"), "{text}");
    }

    #[test]
    fn an_empty_frame_carries_nothing() {
        assert_eq!(payload(&frame(&[])), Ok(&[][..]));
    }
}
