//! `ODOMETRY` from a motion-capture system, read for what the vehicle flies on: the
//! pose, its time, its frames and the estimator type (an extension field).
//!
//! The `mavlink` crate's decoder reads all 230 bytes into enums and covariance arrays the
//! vehicle does not use (0.6 KiB of the firmware's flash); this reads the same wire layout at
//! fixed offsets, checked against the crate's encoding in the tests.

use crate::hil::{HilError, MocapFix, mocap_fix_of};
use crate::msg::{MavEstimatorType, MavFrame, ODOMETRY_DATA};

/// Bytes of the base fields.
const BASE_LEN: usize = ODOMETRY_DATA::ENCODED_LEN;
/// Offsets in the payload (the wire order: by field size, then as declared).
const TIME_USEC: usize = 0;
const POSITION: usize = 8;
const ATTITUDE: usize = 20;
const FRAME_ID: usize = 228;
/// `estimator_type` follows `reset_counter` after the base fields.
const ESTIMATOR_TYPE: usize = BASE_LEN + 1;

/// A motion-capture fix from an `ODOMETRY` payload (as received: MAVLink 2 may have cut its
/// trailing zeros): `None` unless it is motion capture (`MAV_ESTIMATOR_TYPE_MOCAP`) in a
/// local NED or FRD frame, which is what `ATT_POS_MOCAP` carries; its stamp is the sender's.
pub fn mocap_fix(payload: &[u8]) -> Result<Option<MocapFix>, HilError> {
    let mut bytes = [0u8; ESTIMATOR_TYPE + 1];
    let n = payload.len().min(bytes.len());
    bytes[..n].copy_from_slice(&payload[..n]);
    let frame = bytes[FRAME_ID];
    let local = frame == MavFrame::MAV_FRAME_LOCAL_NED as u8
        || frame == MavFrame::MAV_FRAME_LOCAL_FRD as u8;
    if !local || bytes[ESTIMATOR_TYPE] != MavEstimatorType::MAV_ESTIMATOR_TYPE_MOCAP as u8 {
        return Ok(None);
    }
    let f32_at =
        |at: usize| f32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    let position = [f32_at(POSITION), f32_at(POSITION + 4), f32_at(POSITION + 8)];
    let attitude = [
        f32_at(ATTITUDE),
        f32_at(ATTITUDE + 4),
        f32_at(ATTITUDE + 8),
        f32_at(ATTITUDE + 12),
    ];
    let mut stamp = [0u8; 8];
    stamp.copy_from_slice(&bytes[TIME_USEC..TIME_USEC + 8]);
    mocap_fix_of(position, attitude, u64::from_le_bytes(stamp), "ODOMETRY").map(Some)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::{Encoder, Frame};

    fn odometry(frame_id: MavFrame) -> ODOMETRY_DATA {
        ODOMETRY_DATA {
            time_usec: 1_234_567_890,
            x: 1.5,
            y: -2.25,
            z: -0.75,
            q: [0.5, -0.5, 0.5, 0.5],
            vx: 9.0,
            rollspeed: 7.0,
            pose_covariance: [3.0; 21],
            velocity_covariance: [4.0; 21],
            frame_id,
            child_frame_id: MavFrame::MAV_FRAME_BODY_FRD,
            ..Default::default()
        }
    }

    /// The payload as it arrives, with `estimator_type` after the base fields.
    fn sent(m: &ODOMETRY_DATA, estimator_type: MavEstimatorType) -> std::vec::Vec<u8> {
        let mut f = Frame::default();
        Encoder::new(255, 190).encode_extended(m, &[0, estimator_type as u8], &mut f);
        f.payload().to_vec()
    }

    #[test]
    fn reads_the_pose_the_crate_writes() {
        for frame in [MavFrame::MAV_FRAME_LOCAL_NED, MavFrame::MAV_FRAME_LOCAL_FRD] {
            let m = odometry(frame);
            let fix = mocap_fix(&sent(&m, MavEstimatorType::MAV_ESTIMATOR_TYPE_MOCAP))
                .expect("valid")
                .expect("motion capture");
            assert_eq!(fix.stamp_us, m.time_usec);
            let (p, q) = (fix.position, fix.attitude);
            assert_eq!([p.x, p.y, p.z], [m.x, m.y, m.z]);
            assert_eq!([q.w, q.x, q.y, q.z], m.q);
        }
    }

    #[test]
    fn other_estimators_frames_and_missing_extensions_are_not_motion_capture() {
        let m = odometry(MavFrame::MAV_FRAME_LOCAL_NED);
        let vio = sent(&m, MavEstimatorType::MAV_ESTIMATOR_TYPE_VIO);
        assert_eq!(mocap_fix(&vio), Ok(None));
        let global = sent(
            &odometry(MavFrame::MAV_FRAME_GLOBAL),
            MavEstimatorType::MAV_ESTIMATOR_TYPE_MOCAP,
        );
        assert_eq!(mocap_fix(&global), Ok(None));
        let mut base_only = [0u8; 255];
        let n = mavlink::MessageData::ser(&m, mavlink::MavlinkVersion::V2, &mut base_only);
        assert_eq!(mocap_fix(&base_only[..n]), Ok(None));
        assert_eq!(mocap_fix(&[]), Ok(None));
    }

    #[test]
    fn a_pose_that_is_not_finite_is_refused() {
        let mut m = odometry(MavFrame::MAV_FRAME_LOCAL_NED);
        m.q[2] = f32::NAN;
        let bytes = sent(&m, MavEstimatorType::MAV_ESTIMATOR_TYPE_MOCAP);
        assert_eq!(
            mocap_fix(&bytes),
            Err(HilError::NotFinite {
                message: "ODOMETRY"
            })
        );
    }
}
