//! The simulated world the flight software is tested against (docs/system.md#hardware;
//! docs/system.md#paper-cases).
//!
//! A rapier3d rigid body for the payload (its footprint as a thin plate; the support on flat
//! ground is the footprint's convex hull, as docs/models.md has it), with the payload's mass
//! at the scenario's true COM and each robot as a point mass at its rotor. Flat ground with
//! contact and friction, so the payload rests, pivots on an edge and takes off. Rotors push
//! along the body's up axis at their rotor points and twist the body about its z axis by
//! `s_i c_q T_i`; each follows its command through a first-order lag, within its limits, and an
//! optional command-to-thrust map error (the paper's bias: the map over-reads by `map_error`, so
//! the rotor makes `command / map_error`). A smooth body torque disturbance of the scenario's
//! peak acts on roll and pitch.
//!
//! Backlash: each robot hangs in its rack with [`BACKLASH`] of vertical play. Resting (thrust
//! below its weight) it sits on the lower stop and the payload carries it; lifting, it presses
//! on the upper stop and the payload takes its thrust. In between it floats in the gap: the
//! payload carries neither its weight nor its thrust until the play is taken up. This delays
//! a lift's effect on the payload, as on the real rack. The robots can be moved along the rail
//! ([`Plant::set_rotor_points`]).
//!
//! Two departures act on the rotors' thrust when the scenario asks for them: ground effect,
//! each rotor's thrust raised by its rotor's height above the ground ([`ground_effect`]), and
//! the pack's sag, each rotor's thrust for its command lowered by the voltage the rotors'
//! current leaves ([`battery`]). In wind ([`wind`]) the air drags on the rotors, the robots and
//! the payload's edge. The ground touches the plate, and under a hull of more than four corners
//! a small ball at each corner too ([`support`]).
//!
//! Frames: rapier runs directly in the flight software's frames: world NED (gravity along +z,
//! the ground's top face at z = 0) and body FRD, so nothing is converted.

pub mod battery;
pub mod departures;
pub mod dronecan_escs;
pub mod ground_effect;
pub mod sensors;
pub mod support;
pub mod vibration;
pub mod wind;

use rapier3d::prelude::*;
use shared::control::vector::{Quat, Vec3};
use shared::geometry::{Vec2, area_moments};
use shared::scenario::GRAVITY;

/// Rotor time constant, s: a 20 ms first-order lag, typical of 10-inch props on 4S ESCs
/// (5 to 50 ms in the field).
pub const MOTOR_TIME_CONSTANT: f32 = 0.02;
/// A rotor's RPM at its largest thrust (a 10-inch propeller on a 4S motor of about 700 kV
/// makes some 14 N there).
pub const RPM_AT_MAX_THRUST: f32 = 11_000.0;
/// Thickness of the payload plate, m.
pub const PLATE_THICKNESS: f32 = 0.03;
/// Physics step, s (2 kHz: five steps per 400 Hz control tick).
pub const PHYSICS_DT: f32 = 0.0005;
/// Vertical play of each robot in its rack, m.
pub const BACKLASH: f32 = 0.0015;
/// Frequencies of the disturbance on roll and pitch, Hz.
const DISTURBANCE_HZ: [f32; 2] = [0.37, 0.53];

/// What the plant is made of.
#[derive(Clone, Debug)]
pub struct PlantConfig {
    /// Payload outline, body frame, m.
    pub footprint: Vec<Vec2>,
    /// True COM of the payload, m.
    pub com: Vec2,
    /// True payload mass, kg.
    pub mass: f32,
    /// One robot's mass, kg.
    pub robot_mass: f32,
    /// Rotor points, body frame, m.
    pub rotor_points: Vec<Vec2>,
    /// Spin of each rotor.
    pub spin: Vec<i8>,
    /// `c_q / c_t`, m.
    pub torque_per_thrust: f32,
    /// Largest commanded thrust of one rotor, N.
    pub max_thrust: f32,
    /// Command-to-thrust over-read factor (1: exact map).
    pub map_error: f32,
    /// Peak body torque of the disturbance, N m.
    pub disturbance_peak: f32,
    /// Phase of the disturbance (from the run's seed), rad.
    pub disturbance_phase: [f32; 2],
    /// Each rotor's thrust for its command relative to the model's (`[plant]`
    /// `rotor_efficiency_spread`); empty: every rotor as the model.
    pub efficiency: Vec<f32>,
    /// The rotors' first-order lag, s (the model's: [`MOTOR_TIME_CONSTANT`]).
    pub motor_time_constant: f32,
    /// The payload's inertia about its COM relative to the uniform plate's (1: the model).
    pub inertia_scale: f32,
    /// The wind and its gusts ([`wind::Wind`]; calm: the model).
    pub wind: wind::WindConfig,
    /// Whether each rotor's thrust rises near the ground ([`ground_effect`]; off: the model).
    pub ground_effect: bool,
    /// The pack's internal resistance beyond the model pack's, Ohm ([`battery`]; 0: the
    /// model).
    pub pack_resistance: f32,
}

/// The truth, as the sensors see it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrueState {
    /// Position of the payload frame's origin, NED, m.
    pub position: Vec3,
    /// Its velocity, m/s.
    pub velocity: Vec3,
    /// Attitude, body FRD to world NED.
    pub attitude: Quat,
    /// Body rate, rad/s.
    pub rate: Vec3,
}

/// The world: ground, payload, rotors.
pub struct Plant {
    world: PhysicsWorld,
    body: RigidBodyHandle,
    config: PlantConfig,
    thrusts: Vec<f32>,
    /// Each rotor's share of its commanded thrust that it makes (1 healthy, 0 stopped).
    health: Vec<f32>,
    /// Each robot's place in its play (0: lower stop, BACKLASH: upper stop) and speed in it.
    play: Vec<(f32, f32)>,
    /// Physics steps taken: time is counted, not summed, so it never drifts.
    steps: u64,
    /// The air's motion over the payload.
    wind: wind::Wind,
    /// The pack's sag beyond the model pack's in the last step, V.
    sag_volts: f32,
}

/// Mass properties of payload and robots: the payload's mass at its true COM with the inertia
/// of a uniform plate of its footprint, each robot a point mass at its rotor.
fn mass_properties(config: &PlantConfig) -> MassProperties {
    let mid = -0.5 * PLATE_THICKNESS;
    let plate = area_moments(&config.footprint);
    let density = if plate.area > 0.0 {
        config.mass / plate.area
    } else {
        0.0
    };
    let flat = config.mass * PLATE_THICKNESS * PLATE_THICKNESS / 12.0;
    let scale = config.inertia_scale;
    let inertia = Vector::new(
        density * plate.yy + flat,
        density * plate.xx + flat,
        density * (plate.xx + plate.yy),
    ) * scale;
    let mut mass = MassProperties::new(
        Vector::new(config.com.x, config.com.y, mid),
        config.mass,
        inertia,
    );
    for p in &config.rotor_points {
        mass += MassProperties::new(Vector::new(p.x, p.y, mid), config.robot_mass, Vector::ZERO);
    }
    mass
}

/// A rotor's speed, RPM, for its thrust `t` (N): thrust goes with the speed squared, the
/// largest, `max_thrust`, at [`RPM_AT_MAX_THRUST`].
fn rpm_for(t: f32, max_thrust: f32) -> f32 {
    RPM_AT_MAX_THRUST * (t.max(0.0) / max_thrust.max(f32::MIN_POSITIVE)).sqrt()
}

fn vector(v: Vec3) -> Vector {
    Vector::new(v.x, v.y, v.z)
}

fn vec3(v: Vector) -> Vec3 {
    Vec3::new(v.x, v.y, v.z)
}

impl PlantConfig {
    /// What every field the model fixes is in the model: each rotor as commanded, the model's
    /// motor lag, the uniform plate's inertia, no payload, no disturbance (the rest to fill).
    pub const MODEL: Self = Self {
        footprint: Vec::new(),
        com: Vec2::new(0.0, 0.0),
        mass: 0.0,
        robot_mass: 0.0,
        rotor_points: Vec::new(),
        spin: Vec::new(),
        torque_per_thrust: 0.0,
        max_thrust: 0.0,
        map_error: 1.0,
        disturbance_peak: 0.0,
        disturbance_phase: [0.0; 2],
        efficiency: Vec::new(),
        motor_time_constant: MOTOR_TIME_CONSTANT,
        inertia_scale: 1.0,
        wind: wind::WindConfig::CALM,
        ground_effect: false,
        pack_resistance: 0.0,
    };
}

impl Plant {
    /// The configuration, to change before the first step (then [`Self::refresh`]).
    pub fn config_mut(&mut self) -> &mut PlantConfig {
        &mut self.config
    }

    /// The mass properties and the wind made again from the configuration (after
    /// [`Self::config_mut`]).
    pub fn refresh(&mut self) {
        self.wind = wind::Wind::new(&self.config.wind);
        let mass = mass_properties(&self.config);
        if let Some(rb) = self.world.bodies.get_mut(self.body) {
            rb.set_additional_mass_properties(mass, true);
        }
    }

    /// A payload resting on flat ground at the world origin, rotors off.
    pub fn new(config: PlantConfig) -> Self {
        let mut world = PhysicsWorld {
            gravity: Vector::new(0.0, 0.0, GRAVITY),
            ..PhysicsWorld::default()
        };
        world.integration_parameters.dt = PHYSICS_DT;
        let ground = ColliderBuilder::cuboid(50.0, 50.0, 0.5)
            .translation(Vector::new(0.0, 0.0, 0.5))
            .friction(0.8)
            .build();
        world.colliders.insert(ground);

        let mass = mass_properties(&config);
        let body = world.bodies.insert(
            RigidBodyBuilder::dynamic()
                .additional_mass_properties(mass)
                .can_sleep(false)
                .build(),
        );
        let support = support::support(&config.footprint, PLATE_THICKNESS);
        if let Some(shape) = ColliderBuilder::convex_hull(&support.plate) {
            let collider = shape.density(0.0).friction(0.8).build();
            world
                .colliders
                .insert_with_parent(collider, body, &mut world.bodies);
        }
        for foot in support.feet {
            let collider = ColliderBuilder::ball(support::FOOT_RADIUS)
                .translation(foot)
                .density(0.0)
                .friction(0.8)
                .build();
            world
                .colliders
                .insert_with_parent(collider, body, &mut world.bodies);
        }
        let n = config.rotor_points.len();
        let config_wind = config.wind;
        Self {
            world,
            body,
            config,
            thrusts: vec![0.0; n],
            health: vec![1.0; n],
            play: vec![(0.0, 0.0); n],
            steps: 0,
            wind: wind::Wind::new(&config_wind),
            sag_volts: 0.0,
        }
    }

    /// Moves the robots to new rotor points (body frame): their forces and masses follow.
    pub fn set_rotor_points(&mut self, points: &[Vec2]) {
        if points.len() != self.config.rotor_points.len() {
            return;
        }
        self.config.rotor_points = points.to_vec();
        let mass = mass_properties(&self.config);
        if let Some(rb) = self.world.bodies.get_mut(self.body) {
            rb.set_additional_mass_properties(mass, true);
        }
    }

    /// Moves the payload's true COM to `com` (body frame, m): a load that shifts. The mass
    /// properties follow.
    pub fn set_com(&mut self, com: Vec2) {
        self.config.com = com;
        let mass = mass_properties(&self.config);
        if let Some(rb) = self.world.bodies.get_mut(self.body) {
            rb.set_additional_mass_properties(mass, true);
        }
    }

    /// The payload's true COM, body frame, m.
    pub fn com(&self) -> Vec2 {
        self.config.com
    }

    /// Sets the peak of the body-torque disturbance, N m (the mission turns it on in flight:
    /// it is the paper's flight disturbance, not a load on the ground lifts).
    pub fn set_disturbance_peak(&mut self, peak: f32) {
        self.config.disturbance_peak = peak.max(0.0);
    }

    /// Simulated time, s.
    pub fn time(&self) -> f32 {
        (self.steps as f64 * f64::from(PHYSICS_DT)) as f32
    }

    /// Simulated time, microseconds (exact).
    pub fn time_us(&self) -> u64 {
        self.steps * (f64::from(PHYSICS_DT) * 1e6).round() as u64
    }

    /// Each rotor's actual thrust, N.
    pub fn thrusts(&self) -> &[f32] {
        &self.thrusts
    }

    /// How far the pack's voltage fell in the last step beyond the model pack's own sag, V
    /// (the `battery_sag` resistance times the rotors' current; 0 without it).
    pub fn battery_sag_volts(&self) -> f32 {
        self.sag_volts
    }

    /// Total mass of payload and robots, kg.
    pub fn total_mass(&self) -> f32 {
        self.config.mass + self.config.robot_mass * self.config.rotor_points.len() as f32
    }

    /// The disturbance torque at time `t` (body frame), N m.
    pub fn disturbance(&self, t: f32) -> Vec3 {
        let peak = self.config.disturbance_peak;
        let [fx, fy] = DISTURBANCE_HZ;
        let [px, py] = self.config.disturbance_phase;
        let tau = std::f32::consts::TAU;
        Vec3::new(
            peak * (tau * fx * t + px).sin(),
            peak * (tau * fy * t + py).sin(),
            0.0,
        )
    }

    /// Rotor `i` stops now: its thrust is zero at once (the caller commands it zero from
    /// then on).
    pub fn stop_rotor(&mut self, i: usize) {
        if let Some(t) = self.thrusts.get_mut(i) {
            *t = 0.0;
        }
    }

    /// Rotor `i` makes `health` (0 to 1) of the thrust commanded from now on, through its
    /// motor's lag: a damaged propeller or a failing ESC.
    pub fn set_rotor_health(&mut self, i: usize, health: f32) {
        if let Some(h) = self.health.get_mut(i) {
            *h = health.clamp(0.0, 1.0);
        }
    }

    /// Each rotor's RPM as its ESC would report it: thrust goes with the RPM squared, the
    /// largest thrust at [`RPM_AT_MAX_THRUST`].
    pub fn rotor_rpm(&self) -> impl Iterator<Item = f32> + '_ {
        let max = self.config.max_thrust;
        self.thrusts.iter().map(move |&t| rpm_for(t, max))
    }

    /// One physics step of `PHYSICS_DT` with rotor commands `commands` (N, commanded units).
    pub fn step(&mut self, commands: &[f32]) {
        let alpha = (PHYSICS_DT / self.config.motor_time_constant.max(PHYSICS_DT)).min(1.0);
        let mut scale = 1.0 / self.config.map_error;
        if self.config.pack_resistance > 0.0 {
            // The pack's voltage for the rotors' draw now, and the thrust it leaves them.
            let pack = battery::Pack {
                resistance: self.config.pack_resistance,
            };
            let power: f32 = self
                .thrusts
                .iter()
                .map(|&t| battery::electrical_power(t))
                .sum();
            let volts = pack.terminal_volts(power);
            self.sag_volts = battery::PACK_VOLTS - volts;
            scale *= battery::Pack::thrust_factor(volts);
        }
        for (i, ((t, &c), &health)) in self
            .thrusts
            .iter_mut()
            .zip(commands)
            .zip(&self.health)
            .enumerate()
        {
            let efficiency = self.config.efficiency.get(i).copied().unwrap_or(1.0);
            let target = c.clamp(0.0, self.config.max_thrust) * scale * health * efficiency;
            *t += (target - *t) * alpha;
        }
        let disturbance = self.disturbance(self.time());
        let Some(rb) = self.world.bodies.get_mut(self.body) else {
            return;
        };
        rb.reset_forces(false);
        rb.reset_torques(false);
        let pose = *rb.position();
        let rotation = pose.rotation;
        let mut yaw_torque = 0.0;
        let weight = self.config.robot_mass * GRAVITY;
        let rotor_z = -(PLATE_THICKNESS + ground_effect::ROTOR_ABOVE_PLATE);
        for (i, (p, &t)) in self
            .config
            .rotor_points
            .iter()
            .zip(&self.thrusts)
            .enumerate()
        {
            let at = pose * Vector::new(p.x, p.y, -0.5 * PLATE_THICKNESS);
            // Near the ground the rotor makes more for the same power: its plane's height
            // (NED: the ground's top face at z = 0).
            let lift = if self.config.ground_effect {
                let rotor = pose * Vector::new(p.x, p.y, rotor_z);
                t * ground_effect::gain(ground_effect::ROTOR_RADIUS, -rotor.z)
            } else {
                t
            };
            // The robot in its play: its own vertical motion relative to the payload.
            let (mut x, mut v) = self.play[i];
            let net = lift - weight;
            let engaged_up = x >= BACKLASH && net >= 0.0;
            let resting = x <= 0.0 && net <= 0.0;
            let transmitted = if engaged_up || resting {
                v = 0.0;
                lift
            } else {
                v += net / self.config.robot_mass * PHYSICS_DT;
                x = (x + v * PHYSICS_DT).clamp(0.0, BACKLASH);
                // Floating: the payload carries neither the robot's weight nor its thrust.
                weight
            };
            self.play[i] = (x, v);
            let force = rotation * Vector::new(0.0, 0.0, -transmitted);
            rb.add_force_at_point(force, at, true);
            let spin = f32::from(self.config.spin.get(i).copied().unwrap_or(1));
            yaw_torque += spin * self.config.torque_per_thrust * t;
        }
        // The wind's drag: on the payload's edge, each robot's body and each rotor.
        if self.wind.advance(PHYSICS_DT) {
            let mut relative = self.wind.air() - vec3(rb.linvel());
            relative.z = 0.0;
            let relative_body = vec3(rotation.inverse() * vector(relative));
            let plate = wind::plate_drag(
                relative,
                relative_body,
                &self.config.footprint,
                PLATE_THICKNESS,
            );
            let at = pose * Vector::new(plate.at.x, plate.at.y, -0.5 * PLATE_THICKNESS);
            rb.add_force_at_point(vector(plate.force), at, true);
            let axis = vec3(rotation * Vector::new(0.0, 0.0, 1.0));
            let robot = wind::bluff_drag(relative, wind::ROBOT_FRONTAL_AREA);
            for (p, &t) in self.config.rotor_points.iter().zip(&self.thrusts) {
                let omega = rpm_for(t, self.config.max_thrust) * core::f32::consts::TAU / 60.0;
                let force = robot + wind::rotor_drag(relative, axis, omega);
                let at = pose * Vector::new(p.x, p.y, rotor_z);
                rb.add_force_at_point(vector(force), at, true);
            }
        }
        let body_torque = vector(disturbance) + Vector::new(0.0, 0.0, yaw_torque);
        rb.add_torque(rotation * body_torque, true);
        self.world.step();
        self.steps += 1;
    }

    /// The truth at the payload frame's origin.
    pub fn state(&self) -> TrueState {
        let Some(rb) = self.world.bodies.get(self.body) else {
            return TrueState {
                position: Vec3::ZERO,
                velocity: Vec3::ZERO,
                attitude: Quat::IDENTITY,
                rate: Vec3::ZERO,
            };
        };
        let pose = rb.position();
        let r = pose.rotation;
        let attitude = Quat {
            w: r.w,
            x: r.x,
            y: r.y,
            z: r.z,
        };
        let origin = pose.translation;
        let omega = rb.angvel();
        let velocity = rb.linvel() + omega.cross(origin - rb.center_of_mass());
        TrueState {
            position: vec3(origin),
            velocity: vec3(velocity),
            attitude,
            rate: attitude.inverse_rotate(vec3(omega)),
        }
    }
}
