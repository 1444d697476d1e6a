//! The estimation grid over theta = [COM x, COM y, mass]
//! (docs/models.md#grid-posterior-and-stopping-rule: axis `k` has `floor((max - min) / res) + 1`
//! points `min + i * res`), with an optional fourth axis: an unknown thrust-scale factor of the
//! command-to-thrust map, marginalised out.
//!
//! Flat index layout: `((ix * ny + iy) * nm + im) * ns + is`, so the points sharing one COM
//! are contiguous (the lift-off model's geometric part depends on the COM only).

use crate::geometry::Vec2;
use crate::math;
use crate::scenario::{EstimationSetup, MAX_GRID_POINTS};

/// Most values on the thrust-scale axis.
pub const MAX_SCALE_POINTS: usize = 16;

/// An unknown factor `s` by which the command-to-thrust map over-reads: the flight controller
/// believes it applies `s` times the thrust the rotors really make. The measured lift-off
/// command is then `s * lambda(theta)`. Values `min + i * step` up to `max`, uniform prior.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThrustScaleAxis {
    /// Smallest factor.
    pub min: f32,
    /// Largest factor.
    pub max: f32,
    /// Spacing.
    pub step: f32,
}

impl ThrustScaleAxis {
    /// The default bias term: map errors from -10 % to +20 % in steps of 5 %.
    pub const DEFAULT: Self = Self {
        min: 0.9,
        max: 1.2,
        step: 0.05,
    };

    fn len(&self) -> usize {
        math::floor((self.max - self.min) / self.step + 1e-4) as usize + 1
    }
}

/// Why a grid cannot be built.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GridError {
    /// More points than [`MAX_GRID_POINTS`].
    TooManyPoints {
        /// Points asked for.
        points: usize,
    },
    /// The layers just beyond the grid's faces (see [`crate::estimation::guard`]) have more
    /// points than [`crate::estimation::guard::MAX_GUARD_POINTS`].
    TooManyGuardPoints {
        /// Points they would have.
        points: usize,
    },
    /// The thrust-scale axis is malformed (non-positive values or step, max below min, or
    /// more than [`MAX_SCALE_POINTS`] values).
    BadScaleAxis,
}

impl core::fmt::Display for GridError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::TooManyPoints { points } => write!(
                f,
                "the grid has {points} points, at most {MAX_GRID_POINTS} supported"
            ),
            Self::TooManyGuardPoints { points } => write!(
                f,
                "the layers beyond the grid's faces have {points} points, at most {} supported: use fewer grid points",
                crate::estimation::guard::MAX_GUARD_POINTS
            ),
            Self::BadScaleAxis => write!(
                f,
                "thrust-scale axis needs 0 < min <= max, step > 0 and at most {MAX_SCALE_POINTS} values"
            ),
        }
    }
}

impl core::error::Error for GridError {}

/// The grid's axes and index arithmetic.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    setup: EstimationSetup,
    shape: [usize; 3],
    scale: Option<ThrustScaleAxis>,
    scale_len: usize,
}

impl Grid {
    /// No grid: an unloaded estimator's.
    pub(crate) const EMPTY: Self = Self {
        setup: EstimationSetup {
            grid_min: [0.0; 3],
            grid_max: [0.0; 3],
            resolution: [0.0; 3],
            threshold: 0.0,
            noise_sigma: 0.0,
            max_measurements: 0,
        },
        shape: [0; 3],
        scale: None,
        scale_len: 0,
    };

    /// The grid of a checked estimation set-up, with the thrust-scale axis when given.
    pub fn new(setup: &EstimationSetup, scale: Option<ThrustScaleAxis>) -> Result<Self, GridError> {
        let shape = [0, 1, 2].map(|a| setup.axis_len(a));
        let scale_len = match scale {
            None => 1,
            Some(axis) => {
                let ok = axis.min > 0.0
                    && axis.step > 0.0
                    && axis.max >= axis.min
                    && axis.min.is_finite()
                    && axis.max.is_finite()
                    && axis.len() <= MAX_SCALE_POINTS;
                if !ok {
                    return Err(GridError::BadScaleAxis);
                }
                axis.len()
            }
        };
        let points = shape.iter().product::<usize>() * scale_len;
        if points > MAX_GRID_POINTS {
            return Err(GridError::TooManyPoints { points });
        }
        Ok(Self {
            setup: *setup,
            shape,
            scale,
            scale_len,
        })
    }

    /// Points per theta axis.
    pub fn shape(&self) -> [usize; 3] {
        self.shape
    }

    /// Resolution per theta axis.
    pub fn resolution(&self) -> [f32; 3] {
        self.setup.resolution
    }

    /// Number of COM points (`nx * ny`).
    pub fn com_len(&self) -> usize {
        self.shape[0] * self.shape[1]
    }

    /// Number of theta points (`nx * ny * nm`).
    pub fn theta_len(&self) -> usize {
        self.com_len() * self.shape[2]
    }

    /// Number of thrust-scale values (1 without the axis).
    pub fn scale_len(&self) -> usize {
        self.scale_len
    }

    /// Number of points of the whole grid.
    pub fn len(&self) -> usize {
        self.theta_len() * self.scale_len
    }

    /// True when the grid has no point (never, for a checked set-up).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// COM of COM point `com_index` (`ix * ny + iy`).
    pub fn com(&self, com_index: usize) -> Vec2 {
        let (ix, iy) = (com_index / self.shape[1], com_index % self.shape[1]);
        Vec2::new(self.setup.axis_value(0, ix), self.setup.axis_value(1, iy))
    }

    /// Value of point `index` along theta axis `axis` (0: COM x, 1: COM y, 2: mass).
    pub fn axis_value(&self, axis: usize, index: usize) -> f32 {
        self.setup.axis_value(axis, index)
    }

    /// Mass of mass index `im`, kg.
    pub fn mass(&self, im: usize) -> f32 {
        self.setup.axis_value(2, im)
    }

    /// Thrust-scale factor of scale index `is` (1 without the axis).
    pub fn scale(&self, is: usize) -> f32 {
        match self.scale {
            None => 1.0,
            Some(axis) => axis.min + is as f32 * axis.step,
        }
    }

    /// Axis indices `[ix, iy, im]` of theta point `theta_index`.
    pub fn axis_indices(&self, theta_index: usize) -> [usize; 3] {
        let im = theta_index % self.shape[2];
        let com = theta_index / self.shape[2];
        [com / self.shape[1], com % self.shape[1], im]
    }

    /// Theta point index of axis indices `[ix, iy, im]`.
    pub fn theta_index(&self, idx: [usize; 3]) -> usize {
        (idx[0] * self.shape[1] + idx[1]) * self.shape[2] + idx[2]
    }

    /// Theta value `[x, y, mass]` of theta point `theta_index`.
    pub fn theta(&self, theta_index: usize) -> [f32; 3] {
        let idx = self.axis_indices(theta_index);
        [0, 1, 2].map(|a| self.setup.axis_value(a, idx[a]))
    }
}
