//! MAVLink's parameter protocol, vehicle side (MAVLink "Parameter Protocol"), over the
//! mission's table of `shared::mission::params`: every parameter a
//! 32-bit float (`MAV_PARAM_TYPE_REAL32`), numbered in table order.
//!
//! | request | answer |
//! |---|---|
//! | `PARAM_REQUEST_LIST` | `PARAM_VALUE` of every parameter, index 0 to count - 1 |
//! | `PARAM_REQUEST_READ` by index (or by name with index -1) | its `PARAM_VALUE`; an unknown one: a `STATUSTEXT` saying so |
//! | `PARAM_SET` | always a `PARAM_VALUE` with the value now in force: the new one, or the old one kept when the new one is refused (not finite, out of range, not whole, or the mission is running) with a `STATUSTEXT` giving the reason |
//!
//! The service does no I/O: it says what to send and which value changed; the firmware sends
//! and stores it (`onboard::store`).

use core::fmt::Write as _;

use shared::mission::drives::{BoardDrives, TooManyRobots};
use shared::mission::params::{
    COUNT, NAME_LEN, ORIGIN, ORIGIN_LEN, ParamError, ParamValues, TABLE, check, find,
};
use shared::numbers::Num;

use crate::geo::GeoOrigin;
use crate::msg::{
    MavParamType, PARAM_REQUEST_LIST_DATA, PARAM_REQUEST_READ_DATA, PARAM_SET_DATA,
    PARAM_VALUE_DATA,
};
use crate::status::Text;

/// A parameter request addressed to the vehicle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamRequest {
    /// `PARAM_REQUEST_LIST`.
    List,
    /// `PARAM_REQUEST_READ` by index.
    ReadIndex(u16),
    /// `PARAM_REQUEST_READ` by name (index -1).
    ReadName([u8; NAME_LEN]),
    /// `PARAM_SET`.
    Set {
        /// Name, NUL-padded.
        name: [u8; NAME_LEN],
        /// The value asked for.
        value: f32,
    },
}

impl ParamRequest {
    /// The request a `PARAM_REQUEST_LIST` makes.
    pub fn from_list(_m: &PARAM_REQUEST_LIST_DATA) -> Self {
        Self::List
    }

    /// The request a `PARAM_REQUEST_READ` makes.
    pub fn from_read(m: &PARAM_REQUEST_READ_DATA) -> Self {
        match u16::try_from(m.param_index) {
            Ok(index) => Self::ReadIndex(index),
            Err(_) => Self::ReadName(*m.param_id),
        }
    }

    /// The request a `PARAM_SET` makes.
    pub fn from_set(m: &PARAM_SET_DATA) -> Self {
        Self::Set {
            name: *m.param_id,
            value: m.param_value,
        }
    }
}

/// What to send for a request.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamAnswer {
    /// `PARAM_VALUE`s to send: none, one index, or all of them.
    pub values: Values,
    /// A parameter whose value changed (to store).
    pub changed: Option<(usize, f32)>,
    /// A `STATUSTEXT` (warning) explaining a refusal.
    pub text: Option<Text>,
}

/// Which `PARAM_VALUE`s an answer sends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Values {
    /// None.
    None,
    /// The one of this index.
    One(usize),
    /// All, in index order.
    All,
}

/// The parameter service: the values in force and the protocol.
#[derive(Clone, Debug, Default)]
pub struct ParamService {
    values: ParamValues,
    /// The robots of the payload description in use and the board that drives them: an
    /// `ESC_PROTOCOL` with which the board drives fewer is refused
    /// (docs/hardware.md#robots-a-board-drives).
    driven: Option<(usize, BoardDrives)>,
}

/// The parameter the board's rotor count depends on.
const ESC_PROTOCOL: &str = "ESC_PROTOCOL";

fn name_str(name: &[u8; NAME_LEN]) -> &str {
    let end = name.iter().position(|&b| b == 0).unwrap_or(NAME_LEN);
    core::str::from_utf8(&name[..end]).unwrap_or("(not UTF-8)")
}

fn text(args: core::fmt::Arguments<'_>) -> Option<Text> {
    let mut t = Text::new();
    // Cut at the link's longest text.
    let _ = t.write_fmt(args);
    Some(t)
}

impl ParamService {
    /// A service whose values are `values`.
    pub fn new(values: ParamValues) -> Self {
        Self {
            values,
            driven: None,
        }
    }

    /// The values in force.
    pub fn values(&self) -> &ParamValues {
        &self.values
    }

    /// The payload description in use has `robots` robots and `drives` is the board: from now
    /// on an `ESC_PROTOCOL` with which it drives fewer is refused (`robots` 0: none in use).
    pub fn drive_robots(&mut self, robots: usize, drives: BoardDrives) {
        self.driven = (robots > 0).then_some((robots, drives));
    }

    /// Why `value` for parameter `index` would leave robots of the payload in use undriven.
    fn undriven(&self, index: usize, value: f32) -> Option<TooManyRobots> {
        let (robots, drives) = self.driven?;
        if TABLE[index].name != ESC_PROTOCOL || check(index, value).is_err() {
            return None;
        }
        drives.check(robots, value as u8).err()
    }

    /// Answers `request`; `refuse_changes` says why no value may change now (the mission
    /// runs, the request is not signed): then every `PARAM_SET` is answered with the value in
    /// force and that reason.
    pub fn handle(&mut self, request: &ParamRequest, refuse_changes: Option<&str>) -> ParamAnswer {
        let mut answer = ParamAnswer {
            values: Values::None,
            changed: None,
            text: None,
        };
        match *request {
            ParamRequest::List => answer.values = Values::All,
            ParamRequest::ReadIndex(i) if usize::from(i) < COUNT => {
                answer.values = Values::One(usize::from(i));
            }
            ParamRequest::ReadIndex(i) => {
                answer.text = text(format_args!(
                    "param read refused: no parameter {i} (0..{})",
                    COUNT - 1
                ));
            }
            ParamRequest::ReadName(name) => match find(&name) {
                Some(i) => answer.values = Values::One(i),
                None => {
                    answer.text = text(format_args!(
                        "param read refused: no parameter {}",
                        name_str(&name)
                    ));
                }
            },
            ParamRequest::Set { name, value } => {
                let Some(i) = find(&name) else {
                    answer.text = text(format_args!(
                        "param set refused: no parameter {}",
                        name_str(&name)
                    ));
                    return answer;
                };
                answer.values = Values::One(i);
                let spec = &TABLE[i];
                if let Some(why) = refuse_changes {
                    answer.text = text(format_args!("param {} not changed: {why}", spec.name));
                    return answer;
                }
                let old = self.values.get(i);
                let refused = |why: &dyn core::fmt::Display| {
                    text(format_args!(
                        "param {} = {} refused ({why}); kept {} {}",
                        spec.name,
                        Num(value),
                        Num(old.unwrap_or(f32::NAN)),
                        spec.unit
                    ))
                };
                if let Some(why) = self.undriven(i, value) {
                    answer.text = refused(&why);
                    return answer;
                }
                match self.values.set(i, value) {
                    Ok(()) => {
                        if old != Some(value) {
                            answer.changed = Some((i, value));
                        }
                    }
                    Err(e) => answer.text = refused(&e),
                }
            }
        }
        answer
    }

    /// Sets the map origin's parameters (`ORIG_*`) to `origin`, all of them or, when the
    /// table refuses one, none (that one's error). The parameters whose value changed, to
    /// store, in table order.
    pub fn set_origin(
        &mut self,
        origin: &GeoOrigin,
    ) -> Result<heapless::Vec<(usize, f32), ORIGIN_LEN>, ParamError> {
        let values = origin.to_params();
        for (k, &v) in values.iter().enumerate() {
            check(ORIGIN + k, v)?;
        }
        let mut changed = heapless::Vec::new();
        for (k, v) in values.into_iter().enumerate() {
            let i = ORIGIN + k;
            if self.values.get(i) != Some(v) {
                self.values.set(i, v)?;
                // At most ORIGIN_LEN: never full.
                let _ = changed.push((i, v));
            }
        }
        Ok(changed)
    }

    /// The map origin the parameters give now.
    pub fn origin(&self) -> GeoOrigin {
        GeoOrigin::from_params(&self.values)
    }

    /// The `PARAM_VALUE` of parameter `index` (`None` past the table).
    pub fn value_message(&self, index: usize) -> Option<PARAM_VALUE_DATA> {
        value_message(&self.values, index)
    }
}

/// The `PARAM_VALUE` of parameter `index` of `values` (`None` past the table).
pub fn value_message(values: &ParamValues, index: usize) -> Option<PARAM_VALUE_DATA> {
    let value = values.get(index)?;
    Some(PARAM_VALUE_DATA {
        param_value: value,
        param_count: COUNT as u16,
        param_index: index as u16,
        param_id: TABLE[index].name.into(),
        param_type: MavParamType::MAV_PARAM_TYPE_REAL32,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn id(name: &str) -> [u8; NAME_LEN] {
        let mut out = [0u8; NAME_LEN];
        out[..name.len()].copy_from_slice(name.as_bytes());
        out
    }

    #[test]
    fn list_and_reads_answer_with_consistent_indices() {
        let mut s = ParamService::default();
        assert_eq!(s.handle(&ParamRequest::List, None).values, Values::All);
        for (i, spec) in TABLE.iter().enumerate() {
            let m = s.value_message(i).expect("in table");
            assert_eq!((m.param_index as usize, m.param_count as usize), (i, COUNT));
            let by_name = s.handle(&ParamRequest::ReadName(*m.param_id), None);
            assert_eq!(by_name.values, Values::One(i));
            let by_index = s.handle(&ParamRequest::ReadIndex(i as u16), None);
            assert_eq!(by_index.values, Values::One(i));
            assert_eq!(m.param_type, MavParamType::MAV_PARAM_TYPE_REAL32);
            assert_eq!(m.param_value, spec.default_value());
        }
        assert!(s.value_message(COUNT).is_none());
        let past = s.handle(&ParamRequest::ReadIndex(COUNT as u16), None);
        assert_eq!(past.values, Values::None);
        assert!(past.text.is_some_and(|t| t.contains("no parameter")));
    }

    #[test]
    fn a_good_set_changes_the_value_and_answers_with_it() {
        let mut s = ParamService::default();
        let a = s.handle(
            &ParamRequest::Set {
                name: id("MAX_TILT"),
                value: 0.3,
            },
            None,
        );
        let i = find(b"MAX_TILT").expect("exists");
        assert_eq!(a.values, Values::One(i));
        assert_eq!(a.changed, Some((i, 0.3)));
        assert_eq!(a.text, None);
        assert_eq!(s.value_message(i).map(|m| m.param_value), Some(0.3));
        assert_eq!(s.values().config().flight.control.max_tilt, 0.3);
    }

    #[test]
    fn bad_sets_answer_with_the_old_value_and_say_why() {
        let mut s = ParamService::default();
        let i = find(b"LIFT_RAMP").expect("exists");
        let old = TABLE[i].default_value();
        for (value, why) in [
            (f32::NAN, "not a finite number"),
            (f32::NEG_INFINITY, "not a finite number"),
            (1e9, "outside"),
            (-1.0, "outside"),
        ] {
            let a = s.handle(
                &ParamRequest::Set {
                    name: id("LIFT_RAMP"),
                    value,
                },
                None,
            );
            assert_eq!(a.values, Values::One(i), "PARAM_VALUE still sent");
            assert_eq!(a.changed, None);
            let t = a.text.expect("a reason");
            assert!(t.contains("LIFT_RAMP") && t.contains(why), "{t}");
            assert_eq!(s.value_message(i).map(|m| m.param_value), Some(old));
        }
        let running = s.handle(
            &ParamRequest::Set {
                name: id("LIFT_RAMP"),
                value: 2.0,
            },
            Some("the mission is running"),
        );
        assert_eq!(running.changed, None);
        assert!(running.text.is_some_and(|t| t.contains("running")));
        assert_eq!(s.value_message(i).map(|m| m.param_value), Some(old));
        let unknown = s.handle(
            &ParamRequest::Set {
                name: [0xFF; NAME_LEN],
                value: 1.0,
            },
            None,
        );
        assert_eq!(unknown.values, Values::None);
        assert!(unknown.text.is_some());
    }

    #[test]
    fn an_esc_protocol_that_drives_fewer_robots_than_the_payload_has_is_refused() {
        let mut s = ParamService::default();
        let i = find(b"ESC_PROTOCOL").expect("exists");
        let set = |value| ParamRequest::Set {
            name: id("ESC_PROTOCOL"),
            value,
        };
        // A board that drives 12 rotors with DShot600 but 8 with PWM, under a 12-robot payload.
        let board = BoardDrives {
            rotors: [12, 8, 12, 12],
            steppers: 12,
        };
        s.drive_robots(12, board);
        let pwm = s.handle(&set(1.0), None);
        assert_eq!(pwm.changed, None);
        let t = pwm.text.expect("says why");
        assert!(
            t.contains("12 robots; this board drives 8 rotors (ESC_PROTOCOL PWM)"),
            "{t}"
        );
        assert_eq!(s.value_message(i).map(|m| m.param_value), Some(0.0));
        assert_eq!(s.handle(&set(2.0), None).changed, Some((i, 2.0)));
        // With no payload in use any protocol goes.
        s.drive_robots(0, board);
        assert_eq!(s.handle(&set(1.0), None).changed, Some((i, 1.0)));
        // A value out of range keeps its own reason.
        s.drive_robots(12, board);
        let t = s.handle(&set(7.0), None).text.expect("says why");
        assert!(!t.contains("robots"), "{t}");
    }

    #[test]
    fn setting_the_same_value_again_stores_nothing() {
        let mut s = ParamService::default();
        let set = ParamRequest::Set {
            name: id("PLN_HOVER_T"),
            value: TABLE[find(b"PLN_HOVER_T").expect("exists")].default_value(),
        };
        assert_eq!(s.handle(&set, None).changed, None);
    }

    #[test]
    fn an_origin_sets_its_five_parameters_together() {
        let mut s = ParamService::default();
        let sydney = GeoOrigin::from_message(-338_688_123, 1_512_093_456, 58_250).expect("ok");
        let changed = s.set_origin(&sydney).expect("in range");
        assert_eq!(changed.len(), ORIGIN_LEN);
        assert_eq!(changed[0], (ORIGIN, -33.0));
        assert_eq!(changed[1], (ORIGIN + 1, -8_688_123.0));
        assert_eq!(s.origin(), sydney);
        for (i, v) in &changed {
            assert_eq!(s.value_message(*i).map(|m| m.param_value), Some(*v));
        }
        // The same again changes nothing; a new altitude, one parameter.
        assert_eq!(s.set_origin(&sydney).map(|c| c.len()), Ok(0));
        let higher = GeoOrigin {
            alt_m: 60.0,
            ..sydney
        };
        assert_eq!(
            s.set_origin(&higher).map(|c| c.to_vec()),
            Ok(std::vec![(ORIGIN + 4, 60.0)])
        );
        // A value the table refuses changes none of them.
        let deep = GeoOrigin {
            lat_e7: 0,
            alt_m: -5_000.0,
            ..sydney
        };
        assert!(s.set_origin(&deep).is_err());
        assert_eq!(s.origin(), higher);
    }
}
