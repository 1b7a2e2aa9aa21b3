//! Image settings of a 3-D solve: the camera (given, the scene's, or automatic), the resolution
//! and the exposure, checked before the solve ([`ImageSettings::validate`]).
//!
//! The camera convention is Mitsuba 3's `perspective` sensor with
//! `to_world = look_at(eye, target, up)` and `fov_axis = "y"` (`docs/guide/images.md`): the view
//! direction d = normalize(target − eye), image-left = normalize(up × d), image-up = d × left;
//! a point at camera coordinates (x_left, y_up, z) > 0 lands at pixel coordinates
//! ((1 − x_left / (z·a·t)) · W/2, (1 − y_up / (z·t)) · H/2) with t = tan(fov/2) and a = W/H, the
//! pixel (i, j) covering [i, i+1) × [j, j+1), i to the right, j downwards: no mirroring.

use super::raster::PinholeCamera;
use glam::DVec3;

/// The largest accepted image side in pixels.
pub const MAX_RESOLUTION: u32 = 16384;
/// The default vertical field of view in degrees.
pub const DEFAULT_FOV: f64 = 40.0;

/// A camera or image setting that cannot make an image (checked before the solve).
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum CameraError {
    /// A coordinate or the field of view is NaN or infinite.
    #[error("camera {what} is not finite ({value})")]
    NotFinite {
        /// Which value (`eye`, `target`, `up`, `field of view`).
        what: &'static str,
        /// The value as given.
        value: String,
    },
    /// The eye is the target: no view direction.
    #[error("camera eye and target are the same point ({0}): no view direction")]
    EyeIsTarget(String),
    /// The up vector is zero or parallel to the view direction: no image orientation.
    #[error(
        "camera up {up} is parallel to the view direction {dir} (or zero): no image orientation; \
         give another --camera-up"
    )]
    UpParallel {
        /// The up vector.
        up: String,
        /// The view direction.
        dir: String,
    },
    /// The field of view is not in (0, 180) degrees.
    #[error("field of view {0}° is outside (0, 180) degrees")]
    Fov(f64),
    /// A resolution of 0 or above `MAX_RESOLUTION`.
    #[error("image resolution {width}x{height}: each side must be 1 to {MAX_RESOLUTION} pixels")]
    Resolution {
        /// Width.
        width: u32,
        /// Height.
        height: u32,
    },
    /// The exposure is not a positive finite number.
    #[error("exposure {0} is not a positive finite number")]
    Exposure(f64),
    /// Pixel sub-samples out of range.
    #[error("{0} samples per pixel: expected 1 to {MAX_PIXEL_SAMPLES}")]
    PixelSamples(u32),
}

/// The most sub-samples per pixel of [`ImageMode::Pixel`].
pub const MAX_PIXEL_SAMPLES: u32 = 4096;

fn v(p: DVec3) -> String {
    format!("{},{},{}", p.x, p.y, p.z)
}

impl PinholeCamera {
    /// Checks that the camera makes an image: finite values, eye ≠ target, up not parallel to
    /// the view direction (nor zero), field of view in (0, 180) degrees.
    pub fn validate(&self) -> Result<(), CameraError> {
        for (what, p) in [("eye", self.eye), ("target", self.target), ("up", self.up)] {
            if !p.is_finite() {
                return Err(CameraError::NotFinite { what, value: v(p) });
            }
        }
        if !self.fov_y_degrees.is_finite() {
            return Err(CameraError::NotFinite {
                what: "field of view",
                value: self.fov_y_degrees.to_string(),
            });
        }
        let dir = self.target - self.eye;
        let scale = self
            .eye
            .abs()
            .max(self.target.abs())
            .max_element()
            .max(1e-300);
        if dir.length() <= 1e-12 * scale {
            return Err(CameraError::EyeIsTarget(v(self.eye)));
        }
        let (d, u) = (dir.normalize(), self.up.normalize_or_zero());
        if u == DVec3::ZERO || d.cross(u).length() < 1e-6 {
            return Err(CameraError::UpParallel {
                up: v(self.up),
                dir: v(d),
            });
        }
        if !(self.fov_y_degrees > 0.0 && self.fov_y_degrees < 180.0) {
            return Err(CameraError::Fov(self.fov_y_degrees));
        }
        Ok(())
    }

    /// The camera's frame (Mitsuba's `look_at`): image-left, image-up and the view direction,
    /// unit vectors. Only meaningful for a camera that passes [`PinholeCamera::validate`].
    pub fn frame(&self) -> (DVec3, DVec3, DVec3) {
        let d = (self.target - self.eye).normalize();
        let left = self.up.cross(d).normalize();
        (left, d.cross(left), d)
    }

    /// The (unit) direction of the ray through the image point (sx, sy) ∈ [0, 1]², in fractions
    /// of the width and height from the top-left corner, for an image of aspect `w / h`: pixel
    /// (i, j) of W × H has its centre at ((i + ½)/W, (j + ½)/H).
    pub fn ray_direction(&self, sx: f64, sy: f64, aspect: f64) -> DVec3 {
        let (left, up, d) = self.frame();
        let t = (0.5 * self.fov_y_degrees.to_radians()).tan();
        (d + left * ((1.0 - 2.0 * sx) * aspect * t) + up * ((1.0 - 2.0 * sy) * t)).normalize()
    }

    /// The camera of a scene (its published or file camera).
    pub fn of_scene(scene: &scene_sampler::Scene) -> Self {
        let c = scene.camera;
        Self {
            eye: c.eye,
            target: c.target,
            up: c.up,
            fov_y_degrees: c.fov_y_deg,
        }
    }
}

/// Which camera an image is rendered from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CameraChoice {
    /// The scene's own camera (a built-in's, a glTF camera node) when it has one, else
    /// [`CameraChoice::Automatic`]; `fov` replaces its field of view.
    Scene {
        /// Vertical field of view in degrees, if given.
        fov: Option<f64>,
    },
    /// Placed from the scene's geometry and the solved radiosity (`output/autocam.rs`): from
    /// inside closed scenes, framing open ones tightly. `fov`: the vertical field of view to use
    /// (default 40° outside, 60° inside).
    Automatic {
        /// Vertical field of view in degrees, if given.
        fov: Option<f64>,
    },
    /// This camera.
    Given(PinholeCamera),
}

/// One more view of the same solve: a camera and its image file.
#[derive(Clone, Debug, PartialEq)]
pub struct View {
    /// The camera.
    pub camera: PinholeCamera,
    /// The image (.png, .jpg, .jpeg or .exr).
    pub path: std::path::PathBuf,
}

/// How the 3-D images are made: camera, resolution, exposure, extra views.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageSettings {
    /// The camera of the main image (`OutputPaths::image`).
    pub camera: CameraChoice,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Exposure of the tone-mapped outputs (PNG, JPEG, glTF and PLY colours): display value =
    /// clamp(L · exposure), L = B/π. `None`: automatic (the 95th percentile of the lit surfaces'
    /// luminance maps to 0.8; `tonemap::Exposure::auto`).
    pub exposure: Option<f64>,
    /// Further images from other cameras (same solve, same resolution and exposure).
    pub views: Vec<View>,
    /// How the images are made: rasterizing the output mesh, or gathering B per pixel.
    pub mode: ImageMode,
    /// [`ImageMode::Pixel`]: sub-samples per pixel (box filter; 1 is the pixel centre).
    pub pixel_samples: u32,
}

/// How a 3-D image gets its radiosity.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ImageMode {
    /// Rasterize the output mesh with B at its vertices, interpolated (fast; the bake's accuracy).
    #[default]
    Mesh,
    /// B by the output gather at each pixel sub-sample's visible point (`output/pixel.rs`): the
    /// gather's accuracy everywhere, one gather per sub-sample.
    Pixel,
}

impl std::str::FromStr for ImageMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "mesh" => Ok(Self::Mesh),
            "pixel" => Ok(Self::Pixel),
            _ => Err(format!("unknown image mode `{s}` (expected mesh or pixel)")),
        }
    }
}

impl Default for CameraChoice {
    fn default() -> Self {
        Self::Scene { fov: None }
    }
}

impl CameraChoice {
    /// The camera the front ends' options ask for (`--camera-eye`, `--camera-target`,
    /// `--camera-up`, `--fov`, `--auto-camera`): the given one when both the eye and the target
    /// are (field of view `fov`, default [`DEFAULT_FOV`]), else the automatic one when asked for,
    /// else the scene's; `fov` replaces their field of view.
    pub fn from_options(
        eye_target: Option<(DVec3, DVec3)>,
        up: DVec3,
        fov: Option<f64>,
        automatic: bool,
    ) -> Self {
        match eye_target {
            Some((eye, target)) => CameraChoice::Given(PinholeCamera {
                eye,
                target,
                up,
                fov_y_degrees: fov.unwrap_or(DEFAULT_FOV),
            }),
            None if automatic => CameraChoice::Automatic { fov },
            None => CameraChoice::Scene { fov },
        }
    }
}

impl Default for ImageSettings {
    fn default() -> Self {
        Self {
            camera: CameraChoice::default(),
            width: 512,
            height: 512,
            exposure: None,
            views: Vec::new(),
            mode: ImageMode::Mesh,
            pixel_samples: 1,
        }
    }
}

impl ImageSettings {
    /// Checks every camera, the resolution and the exposure.
    pub fn validate(&self) -> Result<(), CameraError> {
        let ok = |s: u32| (1..=MAX_RESOLUTION).contains(&s);
        if !ok(self.width) || !ok(self.height) {
            return Err(CameraError::Resolution {
                width: self.width,
                height: self.height,
            });
        }
        match self.camera {
            CameraChoice::Given(c) => c.validate()?,
            CameraChoice::Automatic { fov: Some(f) } | CameraChoice::Scene { fov: Some(f) }
                if !(f > 0.0 && f < 180.0) =>
            {
                return Err(CameraError::Fov(f));
            }
            _ => {}
        }
        for view in &self.views {
            view.camera.validate()?;
        }
        if let Some(e) = self.exposure {
            if !(e.is_finite() && e > 0.0) {
                return Err(CameraError::Exposure(e));
            }
        }
        if !(1..=MAX_PIXEL_SAMPLES).contains(&self.pixel_samples) {
            return Err(CameraError::PixelSamples(self.pixel_samples));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(eye: DVec3, target: DVec3, up: DVec3, fov: f64) -> PinholeCamera {
        PinholeCamera {
            eye,
            target,
            up,
            fov_y_degrees: fov,
        }
    }

    /// Mitsuba 3's `perspective` sensor, `to_world = look_at(eye, target, up)`, `fov_axis = y`
    /// (src/sensors/perspective.cpp, `Transform4f::look_at`): left = normalize(up × dir), and the
    /// sample position of camera point (x, y, z) is (½ − ½·x/(z·tan(fov_x/2)),
    /// ½ − ½·a·y/(z·tan(fov_x/2))), tan(fov_x/2) = a·tan(fov_y/2), a = W/H, times (W, H).
    #[test]
    fn a_point_lands_on_the_pixel_mitsuba_puts_it_on() {
        use crate::output::raster::project;
        // Looking down −z with y up: world +x is image-right, +y image-up. fov_y 90°, 200×100:
        // (1, 0.5, −2) has x_left = −1, y_up = 0.5, z = 2 → (0.625·200, 0.375·100).
        let c = cam(DVec3::ZERO, DVec3::NEG_Z, DVec3::Y, 90.0);
        let p = project(&c, 200, 100, DVec3::new(1.0, 0.5, -2.0)).unwrap();
        assert!(
            (p.x - 125.0).abs() < 1e-9 && (p.y - 37.5).abs() < 1e-9,
            "{p}"
        );
        assert!((p.z - 2.0).abs() < 1e-12);
        let d = c.ray_direction(0.625, 0.375, 2.0);
        assert!(d.cross(DVec3::new(1.0, 0.5, -2.0).normalize()).length() < 1e-12);
        // Looking down +z with y up (Mitsuba's camera space itself): +x is image-LEFT.
        let c = cam(
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::new(1.0, 2.0, 13.0),
            DVec3::Y,
            40.0,
        );
        let p = project(&c, 100, 100, DVec3::new(2.0, 2.0, 13.0)).unwrap();
        let t = 20f64.to_radians().tan();
        assert!(
            (p.x - 100.0 * 0.5 * (1.0 - 1.0 / (10.0 * t))).abs() < 1e-9,
            "{p}"
        );
        assert!(p.x < 50.0 && (p.y - 50.0).abs() < 1e-9);
        let below = project(&c, 100, 100, DVec3::new(1.0, 1.0, 13.0)).unwrap();
        assert!(below.y > 50.0 && (below.x - 50.0).abs() < 1e-9, "{below}");
        // up = +x looking down −z: left = x × (−z) = +y, image-up = +x.
        let c = cam(DVec3::ZERO, DVec3::NEG_Z, DVec3::X, 60.0);
        let (left, up, _) = c.frame();
        assert!((left - DVec3::Y).length() < 1e-12 && (up - DVec3::X).length() < 1e-12);
        let p = project(&c, 64, 64, DVec3::new(0.3, 0.2, -1.0)).unwrap();
        assert!(p.x < 32.0 && p.y < 32.0, "{p}");
    }

    #[test]
    fn bad_cameras_are_named_errors() {
        let (o, z, y) = (DVec3::ZERO, DVec3::NEG_Z, DVec3::Y);
        assert!(cam(o, z, y, 40.0).validate().is_ok());
        let nan = DVec3::new(f64::NAN, 0.0, 0.0);
        assert!(matches!(
            cam(nan, z, y, 40.0).validate(),
            Err(CameraError::NotFinite { what: "eye", .. })
        ));
        assert!(matches!(
            cam(z, z, y, 40.0).validate(),
            Err(CameraError::EyeIsTarget(_))
        ));
        assert!(matches!(
            cam(o, y, y, 40.0).validate(),
            Err(CameraError::UpParallel { .. })
        ));
        assert!(matches!(
            cam(o, z, DVec3::ZERO, 40.0).validate(),
            Err(CameraError::UpParallel { .. })
        ));
        for fov in [0.0, 180.0, -5.0, 200.0] {
            assert_eq!(cam(o, z, y, fov).validate(), Err(CameraError::Fov(fov)));
        }
        let mut s = ImageSettings {
            width: 0,
            ..Default::default()
        };
        assert!(matches!(s.validate(), Err(CameraError::Resolution { .. })));
        s.width = MAX_RESOLUTION + 1;
        assert!(matches!(s.validate(), Err(CameraError::Resolution { .. })));
        s.width = 64;
        s.exposure = Some(0.0);
        assert_eq!(s.validate(), Err(CameraError::Exposure(0.0)));
    }
}
