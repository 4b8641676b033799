//! The approximate tracers of the seeds, measured beside exact DIRT so that
//! error against run time is a trade and not a row of zeros:
//!
//! * **MMRT** (seed 004): the multiview multilayer A-buffer, fragments at
//!   pixel centres over the cubemap, bucketed in depth, hit within a
//!   thickness;
//! * **one depth layer** at the camera, traced with a thickness, as
//!   screen-space reflections do (the method 004 and 001 improve on).
//!
//! Both are `dirt_cpu::screen_space::ScreenSpace` tracers. [`sweep`] moves
//! one knob at a time around each method's default (resolution, B,
//! thickness, steps per view, and the walk: every pixel or a min/max depth
//! pyramid, which gives the same hits), so each knob's effect on error and
//! time can be read off its own rows.

use dirt_cpu::screen_space::{DEFAULT_THICKNESS, ScreenSpaceParams};
use dirt_math::Vec3;

use crate::measure::Setting;

/// Which approximate method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Method {
    /// The multiview multilayer A-buffer of 004.
    Mmrt,
    /// One depth layer at the camera.
    SingleLayer,
}

impl Method {
    /// The backend name of its rows.
    pub fn name(self) -> &'static str {
        match self {
            Method::Mmrt => "mmrt",
            Method::SingleLayer => "1-layer",
        }
    }
}

/// One setting of an approximate method.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ApproxPoint {
    pub method: Method,
    /// Pixels per side of each view.
    pub resolution: u32,
    /// Depth buckets per pixel (1 for the single layer).
    pub buckets: u32,
    /// Thickness behind every fragment, a fraction of the scene's diagonal.
    pub thickness: f32,
    /// Most pixels marched per view (0: unbounded).
    pub max_steps: u32,
    /// Walk a min/max depth pyramid instead of every pixel (same hits).
    pub hiz: bool,
}

impl ApproxPoint {
    /// MMRT with unbounded steps.
    pub const fn mmrt(resolution: u32, buckets: u32, thickness: f32) -> ApproxPoint {
        ApproxPoint {
            method: Method::Mmrt,
            resolution,
            buckets,
            thickness,
            max_steps: 0,
            hiz: false,
        }
    }

    /// One depth layer at the camera, unbounded steps, walked through its Hi-Z.
    pub const fn single_layer(resolution: u32, thickness: f32) -> ApproxPoint {
        ApproxPoint {
            method: Method::SingleLayer,
            resolution,
            buckets: 1,
            thickness,
            max_steps: 0,
            hiz: true,
        }
    }

    /// The same point marching at most `steps` pixels per view.
    pub const fn steps(self, steps: u32) -> ApproxPoint {
        ApproxPoint {
            max_steps: steps,
            ..self
        }
    }

    /// The tracer's parameters for a scene whose camera eye is `eye`;
    /// `None` for the single layer without an eye.
    pub fn params(&self, eye: Option<Vec3>) -> Option<ScreenSpaceParams> {
        let mut p = match self.method {
            Method::Mmrt => ScreenSpaceParams::mmrt(self.resolution, self.buckets, self.thickness),
            Method::SingleLayer => {
                ScreenSpaceParams::single_layer(eye?, self.resolution, self.thickness)
            }
        };
        p.max_steps = self.max_steps;
        p.hiz = self.hiz;
        Some(p)
    }

    /// What the reports call it, e.g. `r128 B8 th1e-2` (the backend names the method).
    pub fn setting(&self) -> Setting {
        let views = match self.method {
            Method::Mmrt => "cube",
            Method::SingleLayer => "single@camera",
        };
        let mut label = format!("r{}", self.resolution);
        if self.method == Method::Mmrt {
            label += &format!(" B{}", self.buckets);
        }
        label += &format!(" th{:.0e}", self.thickness);
        if self.max_steps > 0 {
            label += &format!(" steps{}", self.max_steps);
        }
        // The walk, where it is not the method's own: MMRT marches pixels, the single layer its Hi-Z.
        match (self.method, self.hiz) {
            (Method::Mmrt, true) => label += " hiz",
            (Method::SingleLayer, false) => label += " linear",
            _ => {}
        }
        Setting {
            label,
            views: views.to_string(),
            resolution: Some(self.resolution),
            buckets: Some(self.buckets),
            tile: None,
        }
    }
}

/// MMRT's default: the resolution and B of DIRT's default, the library's thickness.
pub const MMRT_DEFAULT: ApproxPoint = ApproxPoint::mmrt(128, 8, DEFAULT_THICKNESS);
/// The single layer's default.
pub const SINGLE_LAYER_DEFAULT: ApproxPoint = ApproxPoint::single_layer(256, DEFAULT_THICKNESS);

/// Every knob of each method, one at a time around its default.
pub fn sweep() -> Vec<ApproxPoint> {
    let d = MMRT_DEFAULT;
    let mut v = vec![d];
    for r in [32, 64, 256] {
        v.push(ApproxPoint { resolution: r, ..d });
    }
    for b in [1, 4, 16] {
        v.push(ApproxPoint { buckets: b, ..d });
    }
    for th in [0.001, 0.003, 0.03, 0.1] {
        v.push(ApproxPoint { thickness: th, ..d });
    }
    for steps in [16, 64] {
        v.push(d.steps(steps));
    }
    v.push(ApproxPoint { hiz: true, ..d });
    let s = SINGLE_LAYER_DEFAULT;
    v.push(s);
    for r in [64, 128, 512] {
        v.push(ApproxPoint { resolution: r, ..s });
    }
    for th in [0.001, 0.003, 0.03, 0.1] {
        v.push(ApproxPoint { thickness: th, ..s });
    }
    v.push(s.steps(64));
    v.push(ApproxPoint { hiz: false, ..s });
    v
}

/// A few points for CI and a first look: each default, a lower resolution
/// and a thinner thickness.
pub fn quick() -> Vec<ApproxPoint> {
    vec![
        MMRT_DEFAULT,
        ApproxPoint {
            resolution: 64,
            ..MMRT_DEFAULT
        },
        SINGLE_LAYER_DEFAULT,
        ApproxPoint {
            thickness: 0.001,
            ..SINGLE_LAYER_DEFAULT
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_and_params() {
        assert_eq!(MMRT_DEFAULT.setting().label, "r128 B8 th1e-2");
        assert_eq!(
            SINGLE_LAYER_DEFAULT.steps(64).setting().label,
            "r256 th1e-2 steps64"
        );
        assert!(SINGLE_LAYER_DEFAULT.params(None).is_none());
        let linear = ApproxPoint {
            hiz: false,
            ..SINGLE_LAYER_DEFAULT
        };
        assert_eq!(linear.setting().label, "r256 th1e-2 linear");
        assert!(!linear.params(Some(Vec3::ONE)).expect("eye").hiz);
        let p = SINGLE_LAYER_DEFAULT
            .params(Some(Vec3::ONE))
            .expect("a camera");
        assert_eq!((p.resolution, p.buckets), (256, 1));
        let p = MMRT_DEFAULT
            .steps(16)
            .params(None)
            .expect("no camera needed");
        assert_eq!((p.resolution, p.buckets, p.max_steps), (128, 8, 16));
        // Every swept point is a valid setting, and each appears once.
        let all = sweep();
        for (i, a) in all.iter().enumerate() {
            a.params(Some(Vec3::ONE))
                .expect("params")
                .validate()
                .expect("valid");
            assert!(!all[..i].contains(a), "{a:?} twice");
        }
    }
}
