//! Tests of the parameter table and values: names, ranges, defaults, checks, the table's
//! Markdown.

use super::*;

/// Found writing the `link_input` fuzz target: the derived `PartialEq` compared
/// the storage, where NaN marks a parameter never set, so the defaults did not equal
/// themselves.
#[test]
fn values_compare_by_the_values_in_force() {
    assert_eq!(ParamValues::DEFAULT, ParamValues::DEFAULT);
    let mut set = ParamValues::DEFAULT;
    set.set(0, TABLE[0].default_value())
        .expect("the default is valid");
    assert_eq!(
        set,
        ParamValues::DEFAULT,
        "set to the default equals never set"
    );
    let p = &TABLE[0];
    let other = if p.min != p.default_value() {
        p.min
    } else {
        p.max
    };
    set.set(0, other).expect("the range's ends are valid");
    assert_ne!(set, ParamValues::DEFAULT);
}

#[test]
fn names_are_unique_short_and_in_mavlink_style() {
    for (i, p) in TABLE.iter().enumerate() {
        assert!(p.name.len() <= NAME_LEN, "{} too long", p.name);
        assert!(
            p.name
                .bytes()
                .all(|b| b.is_ascii_uppercase() || b.is_ascii_digit() || b == b'_'),
            "{}",
            p.name
        );
        assert_eq!(find(p.name.as_bytes()), Some(i), "{} not unique", p.name);
        assert!(!p.unit.is_empty());
        #[cfg(feature = "docs")]
        assert!(!p.doc.is_empty());
    }
}

#[test]
fn the_defaults_are_in_range_and_make_the_default_configuration() {
    for (i, p) in TABLE.iter().enumerate() {
        assert_eq!(check(i, p.default_value()), Ok(()), "{}", p.name);
    }
    assert_eq!(ParamValues::DEFAULT.config(), MissionConfig::DEFAULT);
}

#[test]
fn each_parameter_changes_its_own_field_and_no_other() {
    for (i, p) in TABLE.iter().enumerate() {
        if is_origin(i) {
            // The ground link's: no field of the configuration (below).
            continue;
        }
        let mut values = ParamValues::DEFAULT;
        // A value in range that differs from the default.
        let v = if p.default_value() == p.max {
            p.min
        } else {
            p.max
        };
        values.set(i, v).expect("in range");
        let config = values.config();
        assert_eq!((p.get)(&config), v, "{} not written", p.name);
        assert_ne!(config, MissionConfig::DEFAULT, "{} has no effect", p.name);
        for (j, q) in TABLE.iter().enumerate() {
            if j != i {
                assert_eq!(
                    (q.get)(&config),
                    q.default_value(),
                    "{} moved {}",
                    p.name,
                    q.name
                );
            }
        }
    }
}

#[test]
fn bad_values_are_refused_and_the_old_value_kept() {
    let i = find(b"MAX_TILT").expect("exists");
    let mut values = ParamValues::DEFAULT;
    values.set(i, 0.5).expect("in range");
    for bad in [f32::NAN, f32::INFINITY, -0.1, 10.0] {
        assert!(values.set(i, bad).is_err(), "{bad} taken");
        assert_eq!(values.get(i), Some(0.5));
    }
    let c = find(b"MIS_CONFIRM").expect("exists");
    assert_eq!(values.set(c, 2.5), Err(ParamError::NotWhole));
    assert_eq!(values.set(c, 3.0), Ok(()));
    assert_eq!(values.config().confirmations, 3);
    assert_eq!(check(COUNT, 1.0), Err(ParamError::Unknown));
    assert_eq!(values.get(COUNT), None);
}

#[test]
fn names_are_found_with_and_without_padding() {
    let mut id = [0u8; 16];
    id[..9].copy_from_slice(b"LIFT_RAMP");
    assert_eq!(find(&id), Some(1));
    assert_eq!(find(b"LIFT_RAMP"), Some(1));
    assert_eq!(find(b"LIFT_RAM"), None);
    assert_eq!(find(&[0xFF; 16]), None);
}

#[test]
fn the_map_origin_is_five_parameters_of_the_link_alone() {
    let names: [&str; ORIGIN_LEN] = [
        "ORIG_LAT_DEG",
        "ORIG_LAT_E7",
        "ORIG_LON_DEG",
        "ORIG_LON_E7",
        "ORIG_ALT",
    ];
    for (k, name) in names.iter().enumerate() {
        assert_eq!(find(name.as_bytes()), Some(ORIGIN + k));
        assert!(is_origin(ORIGIN + k));
    }
    assert!(!is_origin(ORIGIN - 1) && !is_origin(ORIGIN + ORIGIN_LEN));
    // Every value a 1e-7 degree part takes is exact as a float.
    for i in [ORIGIN + 1, ORIGIN + 3] {
        assert!(TABLE[i].max < 16_777_216.0 && TABLE[i].integer);
    }
    let mut values = ParamValues::DEFAULT;
    for (k, v) in [-33.0, -8_688_000.0, 151.0, 2_093_000.0, 58.5]
        .into_iter()
        .enumerate()
    {
        values.set(ORIGIN + k, v).expect("in range");
        assert_eq!(values.get(ORIGIN + k), Some(v));
    }
    assert_eq!(values.config(), MissionConfig::DEFAULT);
    assert_eq!(
        values.get(ORIGIN + 4).map(f32::to_bits),
        Some(58.5f32.to_bits())
    );
    assert_eq!(TABLE[ORIGIN + 4].default_value(), ORIGIN_DEFAULT_ALT);
}
