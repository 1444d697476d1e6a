//! Tests of the control allocation: the wrench reproduced unsaturated, the equal split, the
//! saturation (yaw given up first), the mixer without rotors, and layouts it cannot control.

use super::*;

/// The paper's rectangle with 8 robots in a balanced formation about an offset COM.
fn layout_points() -> [Vec2; 8] {
    crate::paper::RECT_ROTORS
}
const SPIN: [i8; 8] = crate::paper::ALTERNATING_SPIN;

fn mixer(kind: MixerKind, com: Vec2) -> Mixer {
    let points = layout_points();
    Mixer::build(
        kind,
        &RotorLayout {
            points: &points,
            spin: &SPIN,
            com,
            torque_per_thrust: 0.016,
            max_thrust: 14.2,
        },
    )
    .expect("controllable")
}

fn close(a: &Wrench, b: &Wrench, tol: f32) -> bool {
    (a.thrust - b.thrust).abs() < tol && (a.torque - b.torque).norm() < tol
}

#[test]
fn allocation_reproduces_the_wrench_when_not_saturated() {
    let m = mixer(MixerKind::Allocation, Vec2::new(0.12, 0.01));
    let w = Wrench {
        thrust: 42.0,
        torque: Vec3::new(0.8, -1.5, 0.05),
    };
    let a = m.allocate(&w);
    assert!(!a.saturation.any(), "{:?}", a.saturation);
    assert!(close(&a.achieved, &w, 1e-3), "{:?}", a.achieved);
    assert!(a.thrusts[..8].iter().all(|&t| (0.0..=14.2).contains(&t)));
}

#[test]
fn equal_split_splits_the_collective_and_delivers_the_torque() {
    // About the centroid of the rotors, equal split delivers every axis.
    let points = layout_points();
    let centroid = points.iter().fold(Vec2::default(), |a, &p| a + p) * (1.0 / 8.0);
    let m = mixer(MixerKind::EqualSplit, centroid);
    let hover = m.allocate(&Wrench {
        thrust: 40.0,
        torque: Vec3::ZERO,
    });
    assert!(
        hover.thrusts[..8].iter().all(|&t| (t - 5.0).abs() < 1e-4),
        "{:?}",
        hover.thrusts
    );
    let w = Wrench {
        thrust: 40.0,
        torque: Vec3::new(0.5, 1.0, 0.03),
    };
    let a = m.allocate(&w);
    assert!(
        (a.achieved.torque - w.torque).norm() < 1e-3,
        "{:?}",
        a.achieved
    );
    // Off the centroid, the equal split itself makes a torque: the paper's weakness.
    let off = mixer(MixerKind::EqualSplit, centroid + Vec2::new(0.3, 0.0));
    let a = off.allocate(&Wrench {
        thrust: 40.0,
        torque: Vec3::ZERO,
    });
    assert!(a.achieved.torque.y.abs() > 5.0, "{:?}", a.achieved);
}

/// The search's lines agree with [`Mixer::room`] scale by scale: for saturating wrenches
/// on both mixers and a lost rotor, the largest scale that fits by the lines and by
/// `room` itself (on a 1/1024 lattice) differ by at most one step.
#[test]
fn scaled_room_agrees_with_room_at_every_scale() {
    let com = Vec2::new(0.12, 0.01);
    let mixers = [
        mixer(MixerKind::Allocation, com),
        mixer(MixerKind::EqualSplit, com),
        mixer(MixerKind::Allocation, com)
            .without(1 << 2)
            .expect("flies on"),
    ];
    let mut seed = 12345u32;
    let mut next = || {
        seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (seed >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
    };
    let mut searched = 0;
    for m in &mixers {
        for _ in 0..200 {
            let wrench = Wrench {
                thrust: 40.0 + 60.0 * next().abs(),
                torque: Vec3::new(8.0 * next(), 8.0 * next(), 0.0),
            };
            let n = m.count;
            let (mut thrust, mut tilt) = ([0.0f32; MAX_ROBOTS], [0.0f32; MAX_ROBOTS]);
            for i in 0..n {
                thrust[i] = m.columns[0][i] * wrench.thrust;
                tilt[i] = m.columns[1][i] * wrench.torque.x + m.columns[2][i] * wrench.torque.y;
            }
            let Some(lines) = ScaledRoom::new(m, &thrust, &tilt, &m.columns[0]) else {
                continue;
            };
            let by_room = |scale: f32| {
                let mut base = [0.0f32; MAX_ROBOTS];
                for i in 0..n {
                    base[i] = thrust[i] + scale * tilt[i];
                }
                m.room(&base, &m.columns[0]).is_some()
            };
            let largest = |fits: &dyn Fn(f32) -> bool| {
                (0..=1024u32)
                    .rev()
                    .find(|&k| fits(k as f32 / 1024.0))
                    .unwrap_or(0)
            };
            let (a, b) = (largest(&|x| lines.at(x)), largest(&by_room));
            assert!(
                a.abs_diff(b) <= 1,
                "{wrench:?}: lines {a} / 1024, room {b} / 1024"
            );
            searched += usize::from(b < 1024);
        }
    }
    assert!(
        searched > 50,
        "only {searched} wrenches needed roll and pitch scaled down"
    );
}

#[test]
fn yaw_is_given_up_before_roll_and_pitch() {
    let m = mixer(MixerKind::Allocation, Vec2::new(0.1, 0.0));
    // Near full collective: room for the pitch torque but not for a large yaw as well.
    let w = Wrench {
        thrust: 95.0,
        torque: Vec3::new(0.0, 2.0, 0.4),
    };
    let a = m.allocate(&w);
    assert!(a.saturation.yaw, "{:?}", a.saturation);
    assert!(!a.saturation.roll_pitch, "{:?}", a.saturation);
    assert!(
        (a.achieved.torque.y - 2.0).abs() < 1e-3,
        "pitch delivered: {:?}",
        a.achieved
    );
    assert!(a.achieved.torque.z.abs() < 0.4, "yaw cut: {:?}", a.achieved);
    assert!(
        a.thrusts[..8]
            .iter()
            .all(|&t| (-1e-4..=14.2 + 1e-4).contains(&t))
    );

    // Beyond what fits, roll and pitch are scaled but keep their direction.
    let w = Wrench {
        thrust: 60.0,
        torque: Vec3::new(6.0, 40.0, 0.0),
    };
    let a = m.allocate(&w);
    assert!(a.saturation.roll_pitch);
    let (want, got) = (w.torque, a.achieved.torque);
    assert!(
        (got.x * want.y - got.y * want.x).abs() < 0.05,
        "direction kept: {got:?}"
    );
    assert!(got.y > 0.0 && got.y < want.y);
}

#[test]
fn without_a_rotor_the_others_take_the_wrench() {
    let m = mixer(MixerKind::EqualSplit, Vec2::new(0.12, 0.01));
    for out in 0..8 {
        let d = m.without(1 << out).expect("seven rotors fly");
        assert_eq!(d.kind(), MixerKind::Allocation);
        assert_eq!(d.column(out), [0.0; 4]);
        let w = Wrench {
            thrust: 38.0,
            torque: Vec3::new(0.3, -0.4, 0.0),
        };
        let a = d.allocate(&w);
        assert_eq!(a.thrusts[out], 0.0, "rotor {out} forced to zero");
        assert!(!a.saturation.roll_pitch, "rotor {out}: {:?}", a.saturation);
        assert!(
            (a.achieved.thrust - w.thrust).abs() < 1e-2
                && (a.achieved.torque.x - w.torque.x).abs() < 1e-2
                && (a.achieved.torque.y - w.torque.y).abs() < 1e-2,
            "rotor {out}: {:?}",
            a.achieved
        );
        assert!(a.thrusts[..8].iter().all(|&t| (0.0..=14.2).contains(&t)));
    }
    // Two out as well; the same rotor twice changes nothing.
    let two = m.without(0b1000_0001).expect("six rotors fly");
    assert_eq!(two.column(0), [0.0; 4]);
    assert_eq!(two.column(7), [0.0; 4]);
    assert_eq!(m.without(1).expect("fly").without(1), m.without(1));
}

#[test]
fn without_a_rotor_no_other_is_asked_to_push_down() {
    // A COM near the edge of what the rotors left enclose: the least-norm hover would ask
    // a negative thrust of some; those are not flown, and the hover is all positive.
    let m = mixer(MixerKind::Allocation, Vec2::new(0.45, 0.1));
    for out in 0..8 {
        let Ok(d) = m.without(1 << out) else {
            continue;
        };
        let a = d.allocate(&Wrench {
            thrust: 30.0,
            torque: Vec3::ZERO,
        });
        assert!(a.thrusts[..8].iter().all(|&t| t >= 0.0), "{:?}", a.thrusts);
        // Roll and pitch can still be commanded both ways around the hover.
        for (x, y) in [(0.2, 0.0), (-0.2, 0.0), (0.0, 0.2), (0.0, -0.2)] {
            let a = d.allocate(&Wrench {
                thrust: 30.0,
                torque: Vec3::new(x, y, 0.0),
            });
            assert!(!a.saturation.roll_pitch, "out {out}, ({x}, {y}): {a:?}");
        }
    }
}

#[test]
fn without_rotors_yaw_goes_first_and_a_line_is_uncontrollable() {
    // Four rotors, two of each spin: without both of one spin, no yaw apart from thrust.
    let points = [
        Vec2::new(-1.0, -0.5),
        Vec2::new(1.0, -0.5),
        Vec2::new(1.0, 0.5),
        Vec2::new(-1.0, 0.5),
        Vec2::new(0.0, 0.6),
    ];
    let layout = RotorLayout {
        points: &points,
        spin: &[1, -1, 1, -1, 1],
        // Inside the triangle of rotors 0, 2 and 4.
        com: Vec2::new(0.0, 0.1),
        torque_per_thrust: 0.016,
        max_thrust: 14.2,
    };
    let m = Mixer::build(MixerKind::Allocation, &layout).expect("controllable");
    assert!(m.flies_yaw());
    let no_yaw = m.without(0b01010).expect("three rotors of one spin fly");
    assert!(!no_yaw.flies_yaw());
    let a = no_yaw.allocate(&Wrench {
        thrust: 20.0,
        torque: Vec3::new(0.1, 0.1, 0.05),
    });
    assert!((a.achieved.torque.x - 0.1).abs() < 1e-3, "{a:?}");
    // Rotors 0 and 1 left: one line.
    assert_eq!(m.without(0b11100), Err(AllocationError::Uncontrollable));
}

#[test]
fn rotors_on_one_line_are_uncontrollable() {
    let points = [
        Vec2::new(-1.0, 0.0),
        Vec2::new(0.0, 0.0),
        Vec2::new(1.0, 0.0),
    ];
    let layout = RotorLayout {
        points: &points,
        spin: &[1, -1, 1],
        com: Vec2::default(),
        torque_per_thrust: 0.016,
        max_thrust: 14.2,
    };
    assert_eq!(
        Mixer::build(MixerKind::Allocation, &layout),
        Err(AllocationError::Uncontrollable)
    );
}

#[test]
fn the_authority_at_hover_is_the_largest_torque_each_axis_takes_within_the_rotors_limits() {
    let m = mixer(MixerKind::Allocation, Vec2::new(0.12, 0.01));
    let hover = 42.0;
    let authority = m.authority(hover);
    for axis in 0..3 {
        let reach = [authority.x, authority.y, authority.z][axis];
        assert!(reach > 0.0, "axis {axis}: {authority:?}");
        let torque = |t: f32| {
            let mut v = [0.0f32; 3];
            v[axis] = t;
            Vec3::from_array(v)
        };
        for sign in [1.0, -1.0] {
            // Just within: delivered whole; just beyond, in one direction or the other, cut.
            let within = m.allocate(&Wrench {
                thrust: hover,
                torque: torque(sign * 0.99 * reach),
            });
            assert!(!within.saturation.any(), "axis {axis}: {within:?}");
        }
        let beyond = [1.0, -1.0].map(|sign| {
            m.allocate(&Wrench {
                thrust: hover,
                torque: torque(sign * 1.02 * reach),
            })
            .saturation
            .any()
        });
        assert!(
            beyond.contains(&true),
            "axis {axis}: {reach} N m is the limit"
        );
    }
    // A heavier hover leaves less room.
    let heavy = m.authority(100.0);
    assert!(heavy.x < authority.x && heavy.y < authority.y, "{heavy:?}");
    // At full thrust nothing is left.
    assert_eq!(m.authority(8.0 * 14.2), Vec3::ZERO);
}

#[test]
fn the_interim_mixer_without_a_rotor_gives_it_nothing_and_keeps_the_thrust() {
    let m = mixer(MixerKind::Allocation, Vec2::new(0.12, 0.01));
    for out in [0b100u16, 0b1000_0001] {
        let mut interim = m.clone();
        interim.leave_out(out).expect("rotors left");
        let full = m.without(out).expect("rotors left");
        // The full mixer comes for the same rotors, and is recognised as such, whether or not
        // the mixer flown has left them out yet; not for other rotors left out.
        assert!(interim.same_rotors_except(&full, out), "{out:#b}");
        assert!(m.same_rotors_except(&full, out), "{out:#b}");
        assert!(
            !m.same_rotors_except(&full, 0),
            "{out:#b}: nothing left out"
        );
        assert!(
            !m.same_rotors_except(&full, out | 0b10),
            "{out:#b}: another rotor"
        );
        let w = Wrench {
            thrust: 38.0,
            torque: Vec3::new(0.2, -0.1, 0.0),
        };
        let a = interim.allocate(&w);
        for i in (0..8).filter(|i| out & (1 << i) != 0) {
            assert_eq!(a.thrusts[i], 0.0, "{out:#b}: rotor {i}");
        }
        // The thrust, roll and pitch asked, exactly; no yaw until the full mixer comes.
        assert!(
            (a.achieved.thrust - w.thrust).abs() < 0.01
                && (a.achieved.torque.x - w.torque.x).abs() < 0.01
                && (a.achieved.torque.y - w.torque.y).abs() < 0.01,
            "{out:#b}: {:?}",
            a.achieved
        );
        assert!(!interim.flies_yaw());
        // Seven rotors of 14.2 N hold 38 N level; not more than they make.
        assert!(full.holds_hover(38.0), "{out:#b}");
        assert!(!full.holds_hover(7.0 * 14.2 + 1.0), "{out:#b}");
    }
    // No rotor left with a share of the collective: nothing to fly, the mixer as it was.
    let mut all_out = m.clone();
    assert_eq!(
        all_out.leave_out(0xff),
        Err(AllocationError::Uncontrollable)
    );
    assert_eq!(all_out, m);
}
