//! An environment map: radiance from every direction at infinity, read from an equirectangular
//! (latitude–longitude) HDR image — Mitsuba's `envmap`, pbrt-v4's `ImageInfiniteLight`, Cycles'
//! environment texture, Radiance's `colorpict` on a `glow` source.
//!
//! **Mapping.** Texel column `u ∈ [0, 1)` is the compass bearing φ = 2π·u (0 north, ¼ east, as
//! the sun's azimuth), row `v ∈ [0, 1)` the zenith angle θ = π·v (the top row is the zenith), in
//! the lighting's frame (`up` y: north −Z, east +X — Mitsuba 3's `envmap` convention exactly;
//! `up` z: north +Y, east +X). A rotation of R degrees turns the map clockwise about the zenith
//! seen from above: its north then looks toward bearing R (Mitsuba: `rotate` about the up axis by
//! −R). Each texel is constant radiance over its patch of directions (nearest lookup, as pbrt-v4's
//! image infinite light), so that the sampling density below is exactly proportional to it.
//!
//! **Sampling** (pbrt-v4's `PiecewiseConstant2D` in spherical coordinates): a texel (i, j) is drawn
//! with probability ∝ L̄_ij·Ω_j — its mean radiance over the bands times its solid angle Ω_j =
//! (2π/W)(cos θ_j − cos θ_{j+1}) — and a direction uniform in (φ, cos θ) within it, so the
//! solid-angle density is p(ω) = L̄_ij / Σ L̄·Ω: a texel's samples all carry the same weight
//! L·g/p. With portals ([`EnvMap::with_portals`]) three quarters of the shadow rays go through
//! them, as the sky's (`sky.rs`). MIS with the receivers' cosine rays, as every light.
//!
//! The ground is whatever the map holds below its horizon (most captured maps include it): there is
//! no separate ground glow.

use super::{Light, LightSample, Portals, Receiver, ShadowTarget};
use crate::{BANDS, Bands, Discrete, Result, SceneError};
use glam::DVec3;
use std::f64::consts::PI;
use std::path::Path;

/// The most texels a map may have (8192 × 4096): about 20 bytes each once loaded.
pub const MAX_TEXELS: u64 = 1 << 25;

/// An environment map (module docs).
#[derive(Clone, Debug)]
pub struct EnvMap {
    /// A name for messages (the file).
    name: String,
    width: usize,
    height: usize,
    /// Emission π·L per texel and band, row-major from the zenith row.
    texels: Vec<[f32; 3]>,
    /// (up, north, east) unit vectors.
    frame: [DVec3; 3],
    /// The map's turn about the zenith, radians (module docs).
    rotation: f64,
    /// Rows by Σ_i L̄_ij·Ω_j.
    rows: Discrete,
    /// Columns within each row by L̄_ij (`None` for a black row, never drawn).
    columns: Vec<Option<Discrete>>,
    /// Σ L̄·Ω over the map, of the emission π·L̄ (so `pdf = π·L̄_ij / total`).
    total: f64,
    /// Openings through which interiors see the map.
    portals: Portals,
}

impl EnvMap {
    /// A map of `width × height` texels of radiance `radiance` (row-major from the zenith row),
    /// multiplied by `scale`, in the frame `frame` = (up, north, east), turned by `rotation_deg`.
    ///
    /// # Errors
    /// [`SceneError::Lighting`] for an empty or mismatched size, a negative or non-finite texel or
    /// scale, a frame that is not orthonormal, or a map that is black everywhere.
    pub fn new(
        name: &str,
        (width, height): (usize, usize),
        radiance: &[[f32; 3]],
        frame: (DVec3, DVec3, DVec3),
        rotation_deg: f64,
        scale: f64,
    ) -> Result<Self> {
        let bad = |what: String| SceneError::Lighting {
            message: format!("environment map {name}: {what}"),
        };
        if width == 0 || height == 0 || radiance.len() != width * height {
            return Err(bad(format!("{width}×{height} texels do not form a map")));
        }
        if !(scale.is_finite() && scale >= 0.0 && rotation_deg.is_finite()) {
            return Err(bad("the scale must be ≥ 0 and the rotation finite".into()));
        }
        if let Some(k) = radiance
            .iter()
            .position(|t| t.iter().any(|v| !(v.is_finite() && *v >= 0.0)))
        {
            let (i, j) = (k % width, k / width);
            return Err(bad(format!(
                "texel ({i}, {j}) is negative or not finite: {:?}",
                radiance[k]
            )));
        }
        let (up, north, east) = frame;
        let texels: Vec<[f32; 3]> = radiance
            .iter()
            .map(|t| t.map(|v| (f64::from(v) * scale * PI) as f32))
            .collect();
        let mean = |t: &[f32; 3]| t.iter().map(|v| f64::from(*v)).sum::<f64>() / 3.0;
        let mut columns = Vec::with_capacity(height);
        let mut row_weights = Vec::with_capacity(height);
        for j in 0..height {
            let row: Vec<f64> = texels[j * width..(j + 1) * width]
                .iter()
                .map(mean)
                .collect();
            let d = Discrete::new(&row);
            row_weights
                .push(d.as_ref().map_or(0.0, |d| d.total()) * texel_solid_angle(j, width, height));
            columns.push(d);
        }
        let rows =
            Discrete::new(&row_weights).ok_or_else(|| bad("it is black everywhere".into()))?;
        Ok(Self {
            name: name.into(),
            width,
            height,
            total: rows.total(),
            texels,
            frame: [up, north, east],
            rotation: rotation_deg.to_radians(),
            rows,
            columns,
            portals: Portals::default(),
        })
    }

    /// Reads an equirectangular map from a Radiance `.hdr` (RGBE) or OpenEXR `.exr` file (linear
    /// radiance; an EXR's alpha is ignored), a regular file of at most `MAX_TEXELS` texels —
    /// then [`EnvMap::new`].
    ///
    /// # Errors
    /// The file cannot be read or decoded, is not HDR or EXR, is too large, or a value is bad.
    pub fn read(
        path: &Path,
        frame: (DVec3, DVec3, DVec3),
        rotation_deg: f64,
        scale: f64,
    ) -> Result<Self> {
        let name = path.display().to_string();
        let (size, texels) = read_equirect(path)?;
        Self::new(&name, size, &texels, frame, rotation_deg, scale)
    }

    /// The map seen through `portals` (as [`super::Sky::with_portals`]).
    pub fn with_portals(self, portals: Portals) -> Self {
        Self { portals, ..self }
    }

    /// The texel (column, row) toward the unit direction `dir`.
    fn texel_of(&self, dir: DVec3) -> (usize, usize) {
        let [up, north, east] = self.frame;
        let theta = dir.dot(up).clamp(-1.0, 1.0).acos();
        let bearing = dir.dot(east).atan2(dir.dot(north)) - self.rotation;
        let u = (bearing / (2.0 * PI)).rem_euclid(1.0);
        let i = ((u * self.width as f64) as usize).min(self.width - 1);
        let j = ((theta / PI * self.height as f64) as usize).min(self.height - 1);
        (i, j)
    }

    /// The texel's emission π·L and its band mean.
    fn emission_at(&self, (i, j): (usize, usize)) -> (Bands, f64) {
        let t = self.texels[j * self.width + i];
        let e: Bands = std::array::from_fn(|k| f64::from(t[k.min(2)]));
        (e, e.iter().sum::<f64>() / BANDS as f64)
    }

    /// The map's own density of the unit direction `dir` per steradian.
    fn map_pdf(&self, dir: DVec3) -> f64 {
        self.emission_at(self.texel_of(dir)).1 / self.total
    }

    /// The density of `dir` at the receiver: the map's, mixed with the portals' where they are in
    /// view.
    fn pdf(&self, at: &Receiver, dir: DVec3) -> f64 {
        self.portals.mix_pdf(at.p, dir, self.map_pdf(dir))
    }

    /// A direction drawn from the map by `u ∈ [0, 1)²` (module docs).
    fn sample_map(&self, u: [f64; 2]) -> DVec3 {
        let (j, v) = self.rows.sample_remapped(u[0]);
        let Some(cols) = &self.columns[j] else {
            // a black row has probability 0; only rounding lands here
            return self.frame[0];
        };
        let (i, w) = cols.sample_remapped(u[1]);
        let (c0, c1) = row_cosines(j, self.height);
        let cos_t = (c0 - v * (c0 - c1)).clamp(-1.0, 1.0);
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let bearing = 2.0 * PI * (i as f64 + w) / self.width as f64 + self.rotation;
        let [up, north, east] = self.frame;
        (east * bearing.sin() + north * bearing.cos()) * sin_t + up * cos_t
    }
}

/// cos θ at the top and the bottom of row `j` of `height`.
fn row_cosines(j: usize, height: usize) -> (f64, f64) {
    let c = |j: usize| (PI * j as f64 / height as f64).cos();
    (c(j), c(j + 1))
}

/// The solid angle of one texel of row `j`: (2π/W)(cos θ_j − cos θ_{j+1}).
fn texel_solid_angle(j: usize, width: usize, height: usize) -> f64 {
    let (c0, c1) = row_cosines(j, height);
    2.0 * PI / width as f64 * (c0 - c1)
}

impl Light for EnvMap {
    fn sample(&self, at: &Receiver, u: [f64; 2]) -> Option<LightSample> {
        let w = self.portals.mix_sample(at.p, u, |u| self.sample_map(u))?;
        let (cy, pdf) = (at.n.dot(w), self.pdf(at, w));
        (cy > 0.0 && pdf > 0.0).then(|| LightSample {
            target: ShadowTarget::Direction(w),
            emission: self.emission_at(self.texel_of(w)).0,
            g: cy / PI,
            pdf,
        })
    }

    fn escaped(&self, dir: DVec3) -> Bands {
        self.emission_at(self.texel_of(dir)).0
    }

    fn escaped_pdf(&self, at: &Receiver, dir: DVec3) -> f64 {
        self.pdf(at, dir)
    }

    fn is_delta(&self) -> bool {
        false
    }

    fn is_background(&self) -> bool {
        true
    }

    fn power(&self, radius: f64) -> f64 {
        // the flux through a disc, both sides: ∫ L̄ |cos θ| dω over the sphere ≈ (total/π)/2, as
        // the sky's E_h + π·L_g
        self.portals.collecting_area(radius) * self.total / (2.0 * PI)
    }

    fn is_grey(&self) -> bool {
        self.texels.iter().all(|t| t[0] == t[1] && t[1] == t[2])
    }

    fn describe(&self) -> String {
        format!(
            "environment map {} ({}×{}), mean radiance {:.4}",
            self.name,
            self.width,
            self.height,
            self.total / (4.0 * PI * PI)
        )
    }
}

/// A map's (width, height) in texels.
type Size = (usize, usize);

/// Reads an equirectangular HDR image (`.hdr` or `.exr`): its size and linear RGB texels, row-major
/// from the top row; the size is checked against [`MAX_TEXELS`] from the header, before decoding.
fn read_equirect(path: &Path) -> Result<(Size, Vec<[f32; 3]>)> {
    let name = path.display().to_string();
    let bad = |message: String| SceneError::Lighting {
        message: format!("environment map {name}: {message}"),
    };
    let format = match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
    {
        Some(e) if e == "hdr" || e == "pic" => image::ImageFormat::Hdr,
        Some(e) if e == "exr" => image::ImageFormat::OpenExr,
        _ => return Err(bad("not a .hdr (Radiance RGBE) or .exr file".into())),
    };
    let bytes = crate::confine::read_regular_file(path, crate::confine::DEFAULT_MAX_FILE_BYTES)?;
    let reader = || image::ImageReader::with_format(std::io::Cursor::new(&bytes[..]), format);
    let (w, h) = reader().into_dimensions().map_err(|e| bad(e.to_string()))?;
    if u64::from(w) * u64::from(h) > MAX_TEXELS {
        return Err(bad(format!(
            "{w}×{h} texels is more than the {MAX_TEXELS} this build reads (8192×4096); \
             downsample it"
        )));
    }
    let mut r = reader();
    r.no_limits();
    let img = std::panic::catch_unwind(move || r.decode())
        .map_err(|_| bad("the image decoder failed on this file".into()))?
        .map_err(|e| bad(e.to_string()))?
        .into_rgb32f();
    let texels = img.pixels().map(|p| p.0).collect();
    Ok(((w as usize, h as usize), texels))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame() -> (DVec3, DVec3, DVec3) {
        (DVec3::Y, -DVec3::Z, DVec3::X)
    }

    /// A map with a bright patch, a coloured band and a black row.
    fn patchy() -> EnvMap {
        let (w, h) = (16, 8);
        let mut t = vec![[0.2_f32, 0.3, 0.4]; w * h];
        for i in 0..w {
            t[3 * w + i] = [0.0; 3];
        }
        t[w + 5] = [40.0, 30.0, 20.0];
        t[6 * w + 2] = [5.0, 5.0, 5.0];
        EnvMap::new("patchy", (w, h), &t, frame(), 30.0, 2.0).unwrap()
    }

    /// The sampling density integrates to 1 over the sphere, and the irradiance E·g/p averaged
    /// over the map's own samples equals the irradiance by quadrature of its radiance, for
    /// receivers facing up, down and sideways.
    #[test]
    fn density_and_irradiance_agree_with_quadrature() {
        let map = patchy();
        let sphere = |f: &dyn Fn(DVec3) -> f64| {
            crate::hemisphere_quadrature(DVec3::Y, 800, f)
                + crate::hemisphere_quadrature(-DVec3::Y, 800, f)
        };
        let integral = sphere(&|w| map.map_pdf(w));
        assert!((integral - 1.0).abs() < 2e-3, "∫ pdf = {integral}");
        for n in [DVec3::Y, -DVec3::Y, DVec3::new(0.6, 0.0, 0.8)] {
            let at = Receiver { p: DVec3::ZERO, n };
            let quad = crate::hemisphere_quadrature(n, 800, |w| map.escaped(w)[0] / PI * w.dot(n));
            let m = 300;
            let mut est = 0.0;
            for a in 0..m {
                for b in 0..m {
                    let u = [(a as f64 + 0.5) / m as f64, (b as f64 + 0.5) / m as f64];
                    if let Some(s) = map.sample(&at, u) {
                        est += s.emission[0] * s.g / s.pdf;
                        let back = map.escaped_pdf(
                            &at,
                            match s.target {
                                ShadowTarget::Direction(d) => d,
                                ShadowTarget::Point { .. } => unreachable!(),
                            },
                        );
                        assert!((back / s.pdf - 1.0).abs() < 1e-9, "pdf of the sample");
                    }
                }
            }
            est /= (m * m) as f64;
            assert!((est / quad - 1.0).abs() < 5e-3, "n {n}: {est} vs {quad}");
        }
    }

    /// A constant map of radiance L gives E = π·L to every receiver (the white furnace's light),
    /// and its texel lookup follows the compass: with a rotation of 90°, the map's north column
    /// looks east.
    #[test]
    fn constant_map_and_compass() {
        let map = EnvMap::new("one", (4, 2), &[[1.0; 3]; 8], frame(), 0.0, 1.5).unwrap();
        let at = Receiver {
            p: DVec3::ZERO,
            n: DVec3::new(0.3, -0.5, 0.2).normalize(),
        };
        let e = crate::hemisphere_quadrature(at.n, 200, |w| map.escaped(w)[0] * w.dot(at.n) / PI);
        assert!((e / (PI * 1.5) - 1.0).abs() < 1e-3, "{e}");
        let mut t = vec![[0.0_f32; 3]; 8];
        t[0] = [1.0; 3]; // top row, column 0: bearings 0–90°
        let north = EnvMap::new("n", (4, 2), &t, frame(), 0.0, 1.0).unwrap();
        let east = EnvMap::new("e", (4, 2), &t, frame(), 90.0, 1.0).unwrap();
        let toward = |az: f64| super::super::lighting::Up::Y.direction(az, 45.0);
        assert!(north.escaped(toward(45.0))[0] > 0.0 && north.escaped(toward(135.0))[0] == 0.0);
        assert!(east.escaped(toward(135.0))[0] > 0.0 && east.escaped(toward(45.0))[0] == 0.0);
        assert!(EnvMap::new("black", (4, 2), &[[0.0; 3]; 8], frame(), 0.0, 1.0).is_err());
        assert!(EnvMap::new("nan", (1, 1), &[[f32::NAN; 3]], frame(), 0.0, 1.0).is_err());
    }

    /// `.hdr` and `.exr` files read back as written (RGBE to its 8-bit mantissa), top row first;
    /// a header that promises more than [`MAX_TEXELS`] is refused before decoding, and other
    /// formats by name.
    #[test]
    fn hdr_and_exr_files_read_back() {
        let dir = std::env::temp_dir().join(format!("envmap-read-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let img = image::Rgb32FImage::from_fn(6, 3, |i, j| {
            image::Rgb([i as f32 + 1.0, j as f32 * 10.0 + 0.5, 0.25])
        });
        for (ext, tol) in [("exr", 0.0), ("hdr", 0.01)] {
            let path = dir.join(format!("map.{ext}"));
            img.save(&path).unwrap();
            let ((w, h), t) = read_equirect(&path).unwrap();
            assert_eq!((w, h), (6, 3));
            for (k, texel) in t.iter().enumerate() {
                let want = img.as_raw()[3 * k..3 * k + 3].to_vec();
                for (a, b) in texel.iter().zip(&want) {
                    assert!(
                        (a - b).abs() <= tol * b.abs() + 1e-6,
                        "{ext} {k}: {texel:?} {want:?}"
                    );
                }
            }
            assert!(EnvMap::read(&path, frame(), 0.0, 1.0).is_ok());
        }
        let bomb = dir.join("bomb.hdr");
        std::fs::write(
            &bomb,
            b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 20000 +X 40000\n",
        )
        .unwrap();
        let e = read_equirect(&bomb).unwrap_err().to_string();
        assert!(e.contains("40000×20000") && e.contains("downsample"), "{e}");
        let png = dir.join("map.png");
        std::fs::write(&png, b"not read").unwrap();
        assert!(
            read_equirect(&png)
                .unwrap_err()
                .to_string()
                .contains("not a .hdr")
        );
    }
}
