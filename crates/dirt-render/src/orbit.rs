//! The interactive camera (the viewer's and the web page's): an eye orbiting a target, with +Y up. It is always
//! handed to the renderer as `Camera::look_at(eye, target, fov)`, the camera
//! `dirt render --eye --target --fov` makes, so the numbers the viewer prints
//! reproduce its image.

use crate::Camera;
use dirt_math::Vec3;

use crate::RenderError;

/// Radians per pixel of mouse drag when orbiting.
const ORBIT_PER_PIXEL: f32 = 0.005;
/// Radians per arrow-key press.
pub const ORBIT_PER_KEY: f32 = 10.0_f32 * std::f32::consts::PI / 180.0;
/// Keeps the eye off the poles, where `look_at` with +Y up turns over.
const MAX_PITCH: f32 = 1.55;

/// Eye, target and vertical field of view; `home` is what R returns to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    pub eye: Vec3,
    pub target: Vec3,
    /// Vertical field of view in degrees.
    pub fov: f32,
    home: (Vec3, Vec3, f32),
}

impl Orbit {
    /// An orbit starting (and resetting) at `eye`, `target`, `fov`; refused
    /// where `Camera::look_at` would refuse it.
    pub fn new(eye: Vec3, target: Vec3, fov: f32) -> Result<Self, RenderError> {
        Camera::look_at(eye, target, fov)?;
        Ok(Self {
            eye,
            target,
            fov,
            home: (eye, target, fov),
        })
    }

    /// The starting orbit of `scene`: its camera (or a framing of it) as
    /// `dirt render` places it, with the overrides given; the target is on
    /// the view axis at the depth of the scene's centre.
    pub fn for_scene(
        scene: &dirt_scene::Scene,
        aspect: f32,
        eye: Option<Vec3>,
        target: Option<Vec3>,
        fov: Option<f32>,
    ) -> Result<Self, RenderError> {
        let base = Camera::for_scene(scene, aspect)?;
        let eye = eye.unwrap_or(base.eye);
        let target = target.unwrap_or_else(|| {
            let b = scene.bounds();
            let depth = (b.center() - base.eye).dot(base.forward);
            let depth = if depth > 0.0 {
                depth
            } else {
                (b.extent().length() * 0.5).max(1e-3)
            };
            base.eye + base.forward * depth
        });
        let fov = fov.unwrap_or_else(|| (base.tan_half_fov.atan() * 2.0).to_degrees());
        Self::new(eye, target, fov)
    }

    /// The renderer's camera.
    pub fn camera(&self) -> Result<Camera, RenderError> {
        Camera::look_at(self.eye, self.target, self.fov)
    }

    fn distance(&self) -> f32 {
        (self.eye - self.target).length()
    }

    /// Turns the eye around the target: `yaw` about +Y, `pitch` up or down,
    /// both in radians; the distance stays.
    pub fn rotate(&mut self, yaw: f32, pitch: f32) {
        let offset = self.eye - self.target;
        let r = offset.length();
        if !(r > 0.0) {
            return;
        }
        let cur_pitch = (offset.y / r).clamp(-1.0, 1.0).asin();
        let cur_yaw = offset.x.atan2(offset.z);
        let p = (cur_pitch + pitch).clamp(-MAX_PITCH, MAX_PITCH);
        let y = cur_yaw + yaw;
        let dir = Vec3::new(p.cos() * y.sin(), p.sin(), p.cos() * y.cos());
        self.set_eye(self.target + dir * r);
    }

    /// A mouse drag of `(dx, dy)` pixels: orbit.
    pub fn drag_orbit(&mut self, dx: f32, dy: f32) {
        self.rotate(-dx * ORBIT_PER_PIXEL, dy * ORBIT_PER_PIXEL);
    }

    /// A mouse drag of `(dx, dy)` pixels in a window `height` pixels high:
    /// eye and target move together in the image plane, so the point under
    /// the cursor at the target's depth follows it.
    pub fn drag_pan(&mut self, dx: f32, dy: f32, height: f32) {
        let Ok(cam) = self.camera() else { return };
        let per_pixel = 2.0 * self.distance() * cam.tan_half_fov / height.max(1.0);
        let shift = (-cam.right * dx + cam.up * dy) * per_pixel;
        if shift.is_finite() {
            self.eye += shift;
            self.target += shift;
        }
    }

    /// Wheel steps (positive: towards the target); each step 10% of the distance.
    pub fn zoom(&mut self, steps: f32) {
        let offset = self.eye - self.target;
        let scaled = offset * 0.9f32.powf(steps);
        // Never onto the target: look_at needs them apart.
        if scaled.length() > 1e-4 * offset.length().max(1e-6) && scaled.is_finite() {
            self.set_eye(self.target + scaled);
        }
    }

    /// Back to where the viewer started.
    pub fn reset(&mut self) {
        (self.eye, self.target, self.fov) = self.home;
    }

    /// Moves the eye unless that would make a camera `look_at` refuses.
    fn set_eye(&mut self, eye: Vec3) {
        if Camera::look_at(eye, self.target, self.fov).is_ok() {
            self.eye = eye;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn orbit() -> Orbit {
        Orbit::new(Vec3::new(0.0, 1.0, 5.0), Vec3::new(0.0, 1.0, 0.0), 45.0).expect("orbit")
    }

    #[test]
    fn rotating_keeps_the_distance_and_the_target() {
        let mut o = orbit();
        o.rotate(ORBIT_PER_KEY, 0.0);
        assert!((o.distance() - 5.0).abs() < 1e-4);
        assert_eq!(o.target, Vec3::new(0.0, 1.0, 0.0));
        assert!(o.eye.x > 0.5, "{:?}", o.eye);
        o.rotate(0.0, 10.0);
        let up = (o.eye - o.target).normalize().y;
        assert!(up < MAX_PITCH.sin() + 1e-4, "clamped off the pole: {up}");
        assert!(o.camera().is_ok());
    }

    #[test]
    fn pan_moves_both_zoom_scales_and_reset_returns() {
        let mut o = orbit();
        o.drag_pan(10.0, 0.0, 100.0);
        assert!(o.eye.x < 0.0 && o.target.x < 0.0, "{o:?}");
        assert!((o.distance() - 5.0).abs() < 1e-4);
        o.zoom(1.0);
        assert!((o.distance() - 4.5).abs() < 1e-4);
        o.zoom(1e9);
        assert!(o.distance() > 0.0 && o.camera().is_ok());
        o.reset();
        assert_eq!(o, orbit());
    }

    #[test]
    fn a_bad_start_is_an_error() {
        assert!(Orbit::new(Vec3::ZERO, Vec3::ZERO, 45.0).is_err());
        assert!(Orbit::new(Vec3::ZERO, Vec3::X, 0.0).is_err());
    }
}
