//! The pinhole (or orthographic) camera that makes primary rays.

use crate::RenderError;
use dirt_math::{Ray, Vec3};
use dirt_scene::{CameraKind, Scene};

/// A camera with an orthonormal frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub forward: Vec3,
    pub up: Vec3,
    pub right: Vec3,
    /// Perspective: `tan(yfov / 2)`. Orthographic: unused.
    pub tan_half_fov: f32,
    /// Orthographic half height (`None`: perspective).
    pub ortho_half_height: Option<f32>,
}

impl Camera {
    /// A perspective camera at `eye` looking at `target`, vertical field of
    /// view `yfov_degrees`.
    pub fn look_at(eye: Vec3, target: Vec3, yfov_degrees: f32) -> Result<Self, RenderError> {
        if !(eye.is_finite() && target.is_finite()) {
            return Err(RenderError::BadCamera(
                "eye and target must be finite".into(),
            ));
        }
        if !(yfov_degrees > 0.0 && yfov_degrees < 180.0) {
            return Err(RenderError::BadCamera(format!(
                "field of view must be in (0, 180) degrees, got {yfov_degrees}"
            )));
        }
        let forward = (target - eye).normalize_or_zero();
        if forward == Vec3::ZERO {
            return Err(RenderError::BadCamera("eye and target coincide".into()));
        }
        Ok(Self::from_frame(
            eye,
            forward,
            Vec3::Y,
            (yfov_degrees.to_radians() * 0.5).tan(),
        ))
    }

    fn from_frame(eye: Vec3, forward: Vec3, up_hint: Vec3, tan_half_fov: f32) -> Self {
        let mut up = Vec3::ZERO;
        for cand in [up_hint, Vec3::Y, Vec3::Z, Vec3::X] {
            let u = cand - forward * cand.dot(forward);
            if u.length_squared() > 1e-8 {
                up = u.normalize();
                break;
            }
        }
        let right = forward.cross(up).normalize_or_zero();
        Self {
            eye,
            forward,
            up,
            right,
            tan_half_fov,
            ortho_half_height: None,
        }
    }

    /// The scene's first camera, else [`framing`](Self::framing) for an image
    /// of the given aspect (width / height).
    pub fn for_scene(scene: &Scene, aspect: f32) -> Result<Self, RenderError> {
        if let Some(c) = scene.cameras.first()
            && c.position.is_finite()
            && c.forward.is_finite()
            && c.forward != Vec3::ZERO
        {
            return Ok(match c.kind {
                CameraKind::Perspective if c.yfov_radians > 0.0 && c.yfov_radians < 3.1 => {
                    Self::from_frame(c.position, c.forward, c.up, (c.yfov_radians * 0.5).tan())
                }
                CameraKind::Orthographic { ymag, .. } if ymag > 0.0 && ymag.is_finite() => Self {
                    ortho_half_height: Some(ymag),
                    ..Self::from_frame(c.position, c.forward, c.up, 1.0)
                },
                _ => Self::framing(scene, aspect)?,
            });
        }
        Self::framing(scene, aspect)
    }

    /// A view of the whole bounding box from the front (+Z), slightly above
    /// and to the right, 45° vertical field of view, as close as keeps every
    /// corner of the box inside an image of the given aspect (width / height).
    pub fn framing(scene: &Scene, aspect: f32) -> Result<Self, RenderError> {
        let b = scene.bounds();
        if b.is_empty() {
            return Err(RenderError::EmptyScene);
        }
        let center = b.center();
        let fov = 45.0f32;
        let tan = (fov.to_radians() * 0.5).tan();
        let aspect = if aspect.is_finite() && aspect > 0.0 {
            aspect
        } else {
            4.0 / 3.0
        };
        let dir = Vec3::new(0.35, 0.35, 1.0).normalize();
        let probe = Self::look_at(center + dir, center, fov)?;
        let mut dist = 0.0f32;
        for i in 0..8 {
            let c = Vec3::new(
                if i & 1 == 0 { b.min.x } else { b.max.x },
                if i & 2 == 0 { b.min.y } else { b.max.y },
                if i & 4 == 0 { b.min.z } else { b.max.z },
            );
            let o = c - center;
            let z = o.dot(probe.forward);
            dist = dist
                .max(o.dot(probe.right).abs() / (tan * aspect) - z)
                .max(o.dot(probe.up).abs() / tan - z);
        }
        let dist = (dist * 1.05).max(b.extent().length() * 0.01).max(1e-6);
        Self::look_at(center + dir * dist, center, fov)
    }

    /// The ray through image point `(x, y)` in pixels (`(0, 0)` the top-left
    /// corner of the image) of a `width`x`height` image.
    pub fn ray(&self, x: f32, y: f32, width: u32, height: u32) -> Ray {
        let aspect = width as f32 / height as f32;
        let sx = (x / width as f32) * 2.0 - 1.0;
        let sy = 1.0 - (y / height as f32) * 2.0;
        match self.ortho_half_height {
            None => {
                let dir = self.forward
                    + self.right * (sx * self.tan_half_fov * aspect)
                    + self.up * (sy * self.tan_half_fov);
                Ray::new(self.eye, dir.normalize(), 0.0, f32::INFINITY)
            }
            Some(h) => {
                let o = self.eye + self.right * (sx * h * aspect) + self.up * (sy * h);
                Ray::new(o, self.forward, 0.0, f32::INFINITY)
            }
        }
    }

    /// Projects a world point to image coordinates in pixels and its depth
    /// along `forward`; `None` behind `near` (perspective only).
    pub fn project(&self, p: Vec3, width: u32, height: u32, near: f32) -> Option<(f32, f32, f32)> {
        let d = p - self.eye;
        let z = d.dot(self.forward);
        if !(z > near) || self.ortho_half_height.is_some() {
            return None;
        }
        let aspect = width as f32 / height as f32;
        let sx = d.dot(self.right) / (z * self.tan_half_fov * aspect);
        let sy = d.dot(self.up) / (z * self.tan_half_fov);
        Some((
            (sx + 1.0) * 0.5 * width as f32,
            (1.0 - sy) * 0.5 * height as f32,
            z,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_looks_forward_and_projection_inverts_rays() {
        let c = Camera::look_at(Vec3::new(0.0, 1.0, 3.0), Vec3::new(0.0, 1.0, 0.0), 60.0)
            .expect("camera");
        let r = c.ray(50.0, 25.0, 100, 50);
        assert!((r.dir() - Vec3::NEG_Z).length() < 1e-6);
        let r = c.ray(20.0, 10.0, 100, 50);
        let p = r.at(2.5);
        let (x, y, _) = c.project(p, 100, 50, 1e-3).expect("in front");
        assert!(
            (x - 20.0).abs() < 1e-3 && (y - 10.0).abs() < 1e-3,
            "{x} {y}"
        );
        assert!(Camera::look_at(Vec3::ZERO, Vec3::ZERO, 60.0).is_err());
        assert!(Camera::look_at(Vec3::ZERO, Vec3::X, 0.0).is_err());
    }
}
