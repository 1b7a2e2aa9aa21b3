//! Probe points: where every solver reports radiosity (FORMATS.md).
//!
//! 3-D: one probe per line, `x y z nx ny nz` (Radiance `rtrace` order); Flatland: `x y nx ny`. Blank lines and
//! lines starting with `#` are skipped. The normal selects the side: a probe snaps to the nearest face whose
//! front normal points the same way (`n_face · n_probe > 0`), and a probe farther than the tolerance from every
//! such face is an error.

use crate::nearest::NearestFaces;
use crate::{FlatPoint, FlatlandScene, Result, Scene, SceneError, SurfacePoint};
use glam::{DVec2, DVec3};
use std::path::Path;

/// A 3-D probe as read from a file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Probe {
    /// Position.
    pub point: DVec3,
    /// Normal (selects the side; normalized on parse).
    pub normal: DVec3,
    /// 1-based line in its file (for messages).
    pub line: usize,
}

/// A Flatland probe as read from a file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlatProbe {
    /// Position.
    pub point: DVec2,
    /// Normal (normalized on parse).
    pub normal: DVec2,
    /// 1-based line in its file.
    pub line: usize,
}

fn parse_numbers(source: &str, text: &str, n: usize) -> Result<Vec<(usize, Vec<f64>)>> {
    let mut out = Vec::new();
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let l = raw.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let vals: Vec<f64> = l
            .split_whitespace()
            .map(|w| w.parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|e| SceneError::ProbeParse {
                source_name: source.into(),
                line,
                message: e.to_string(),
            })?;
        check_numbers(source, line, &vals, n)?;
        out.push((line, vals));
    }
    Ok(out)
}

/// Checks one probe's numbers: `n` of them, all finite.
fn check_numbers(source: &str, line: usize, vals: &[f64], n: usize) -> Result<()> {
    let message = if vals.len() != n {
        format!("expected {n} numbers, found {}", vals.len())
    } else if !vals.iter().all(|v| v.is_finite()) {
        "non-finite value".into()
    } else {
        return Ok(());
    };
    Err(SceneError::ProbeParse {
        source_name: source.into(),
        line,
        message,
    })
}

/// The error of a probe whose normal is zero.
fn zero_normal(source: &str, line: usize) -> SceneError {
    SceneError::ProbeParse {
        source_name: source.into(),
        line,
        message: "zero normal".into(),
    }
}

/// A 3-D probe from its six numbers `x y z nx ny nz` (checked finite), normal normalized.
fn probe_3d(source: &str, line: usize, v: &[f64]) -> Result<Probe> {
    let n = DVec3::new(v[3], v[4], v[5]);
    if n.length_squared() == 0.0 {
        return Err(zero_normal(source, line));
    }
    Ok(Probe {
        point: DVec3::new(v[0], v[1], v[2]),
        normal: n.normalize(),
        line,
    })
}

/// A Flatland probe from its four numbers `x y nx ny` (checked finite), normal normalized.
fn probe_flat(source: &str, line: usize, v: &[f64]) -> Result<FlatProbe> {
    let n = DVec2::new(v[2], v[3]);
    if n.length_squared() == 0.0 {
        return Err(zero_normal(source, line));
    }
    Ok(FlatProbe {
        point: DVec2::new(v[0], v[1]),
        normal: n.normalize(),
        line,
    })
}

/// Parses 3-D probes (`x y z nx ny nz` per line). `source` names the file in messages.
pub fn parse_probes(source: &str, text: &str) -> Result<Vec<Probe>> {
    (parse_numbers(source, text, 6)?.into_iter())
        .map(|(line, v)| probe_3d(source, line, &v))
        .collect()
}

/// Parses Flatland probes (`x y nx ny` per line).
pub fn parse_flat_probes(source: &str, text: &str) -> Result<Vec<FlatProbe>> {
    (parse_numbers(source, text, 4)?.into_iter())
        .map(|(line, v)| probe_flat(source, line, &v))
        .collect()
}

/// 3-D probes from rows of `x y z nx ny nz` held in memory (a caller's arrays), checked as a
/// probe file's lines are: row i is "line" i + 1 of `source` in messages.
pub fn probes_from_rows(source: &str, rows: &[[f64; 6]]) -> Result<Vec<Probe>> {
    (rows.iter().enumerate())
        .map(|(i, v)| {
            check_numbers(source, i + 1, v, 6)?;
            probe_3d(source, i + 1, v)
        })
        .collect()
}

/// Flatland probes from rows of `x y nx ny` held in memory, as [`probes_from_rows`].
pub fn flat_probes_from_rows(source: &str, rows: &[[f64; 4]]) -> Result<Vec<FlatProbe>> {
    (rows.iter().enumerate())
        .map(|(i, v)| {
            check_numbers(source, i + 1, v, 4)?;
            probe_flat(source, i + 1, v)
        })
        .collect()
}

/// A probe file's text: a regular file (not `/dev/zero` or a FIFO) within the default bound on file
/// size ([`crate::LoadOptions::max_file_bytes`]).
fn read(path: &Path) -> Result<String> {
    crate::confine::read_regular_text(path, crate::confine::DEFAULT_MAX_FILE_BYTES)
}

/// Reads a 3-D probe file.
pub fn read_probes(path: impl AsRef<Path>) -> Result<Vec<Probe>> {
    let p = path.as_ref();
    parse_probes(&p.display().to_string(), &read(p)?)
}

/// Reads a Flatland probe file.
pub fn read_flat_probes(path: impl AsRef<Path>) -> Result<Vec<FlatProbe>> {
    let p = path.as_ref();
    parse_flat_probes(&p.display().to_string(), &read(p)?)
}

/// Writes probes in the file format (one `x y z nx ny nz` line each, full precision).
pub fn format_probes(probes: &[Probe]) -> String {
    probes
        .iter()
        .map(|p| {
            format!(
                "{} {} {} {} {} {}\n",
                p.point.x, p.point.y, p.point.z, p.normal.x, p.normal.y, p.normal.z
            )
        })
        .collect()
}

/// Writes Flatland probes (`x y nx ny` per line).
pub fn format_flat_probes(probes: &[FlatProbe]) -> String {
    probes
        .iter()
        .map(|p| {
            format!(
                "{} {} {} {}\n",
                p.point.x, p.point.y, p.normal.x, p.normal.y
            )
        })
        .collect()
}

/// The default snapping tolerance: `1e-4 ·` the scene diagonal.
pub fn default_tolerance(diagonal: f64) -> f64 {
    1e-4 * diagonal
}

/// Snaps many probes against one scene: the nearest-face tree ([`NearestFaces`]) is built once, each
/// probe then costs O(log faces) instead of a scan of every face.
#[derive(Clone, Debug)]
pub struct ProbeSnapper<'a> {
    scene: &'a Scene,
    tree: NearestFaces,
}

impl<'a> ProbeSnapper<'a> {
    /// Builds the snapper's tree over `scene`'s faces.
    pub fn new(scene: &'a Scene) -> Self {
        Self {
            scene,
            tree: NearestFaces::new(scene),
        }
    }

    /// Snaps a probe to the nearest point of a face whose front side faces the probe's normal
    /// (`n_face · n_probe > 0`), if within `tolerance`; among equally near faces the lowest index.
    /// `source` names the probe file in the error, which gives the distance to the nearest such face.
    pub fn snap(&self, probe: &Probe, tolerance: f64, source: &str) -> Result<SurfacePoint> {
        let faces = &self.scene.faces;
        let admit = |f: u32| faces[f as usize].normal.dot(probe.normal) > 0.0;
        match self.tree.nearest(self.scene, probe.point, tolerance, admit) {
            Some(n) => Ok(SurfacePoint {
                point: n.point,
                normal: faces[n.face as usize].normal,
                face: n.face,
            }),
            None => Err(SceneError::ProbeOffSurface {
                source_name: source.into(),
                line: probe.line,
                distance: self
                    .tree
                    .nearest(self.scene, probe.point, f64::INFINITY, admit)
                    .map_or(f64::INFINITY, |n| n.distance),
                tolerance,
            }),
        }
    }
}

impl Scene {
    /// Snaps one probe ([`ProbeSnapper::snap`]; many probes: build one [`ProbeSnapper`]).
    pub fn snap_probe(&self, probe: &Probe, tolerance: f64, source: &str) -> Result<SurfacePoint> {
        ProbeSnapper::new(self).snap(probe, tolerance, source)
    }

    /// Snaps every probe with the default tolerance (error on the first that fails).
    pub fn snap_probes(&self, probes: &[Probe], source: &str) -> Result<Vec<SurfacePoint>> {
        let tol = default_tolerance(self.diagonal());
        let snapper = ProbeSnapper::new(self);
        probes
            .iter()
            .map(|p| snapper.snap(p, tol, source))
            .collect()
    }
}

impl FlatlandScene {
    /// Snaps a Flatland probe to the nearest segment whose front faces the probe's normal, within `tolerance`.
    pub fn snap_probe(&self, probe: &FlatProbe, tolerance: f64, source: &str) -> Result<FlatPoint> {
        let mut best: Option<(f64, usize, DVec2)> = None;
        for (i, s) in self.segments.iter().enumerate() {
            if s.normal.dot(probe.normal) <= 0.0 {
                continue;
            }
            let c = s.point(s.closest_t(probe.point));
            let d = (c - probe.point).length();
            if best.is_none_or(|(bd, _, _)| d < bd) {
                best = Some((d, i, c));
            }
        }
        match best {
            Some((d, i, c)) if d <= tolerance => Ok(FlatPoint {
                point: c,
                normal: self.segments[i].normal,
                segment: i as u32,
            }),
            other => Err(SceneError::ProbeOffSurface {
                source_name: source.into(),
                line: probe.line,
                distance: other.map_or(f64::INFINITY, |b| b.0),
                tolerance,
            }),
        }
    }
    /// Snaps every probe with the default tolerance.
    pub fn snap_probes(&self, probes: &[FlatProbe], source: &str) -> Result<Vec<FlatPoint>> {
        let tol = default_tolerance(self.diagonal());
        probes
            .iter()
            .map(|p| self.snap_probe(p, tol, source))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_in_memory_are_checked_as_a_files_lines() {
        let text = "1 2 3 0 0 2\n4 5 6 0 3 0\n";
        let rows = [
            [1.0, 2.0, 3.0, 0.0, 0.0, 2.0],
            [4.0, 5.0, 6.0, 0.0, 3.0, 0.0],
        ];
        assert_eq!(
            probes_from_rows("p", &rows).unwrap(),
            parse_probes("p", text).unwrap()
        );
        let bad = [rows[0], [4.0, 5.0, 6.0, 0.0, 0.0, 0.0]];
        let e = probes_from_rows("points", &bad).unwrap_err().to_string();
        assert_eq!(e, "points:2: bad probe: zero normal");
        let nan = [[f64::NAN, 0.0, 0.0, 0.0, 1.0, 0.0]];
        let e = probes_from_rows("points", &nan).unwrap_err().to_string();
        assert_eq!(e, "points:1: bad probe: non-finite value");
        let flat = flat_probes_from_rows("f", &[[1.0, 2.0, 0.0, 5.0]]).unwrap();
        assert_eq!(flat, parse_flat_probes("f", "1 2 0 5").unwrap());
    }
}
