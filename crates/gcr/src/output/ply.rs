//! PLY (ASCII) writer: positions, 8-bit sRGB display colours, and the raw radiosity per vertex.

use crate::mesh::ShadedMesh;
use crate::output::tonemap::Exposure;
use std::io::Write;

/// Writes `mesh` as ASCII PLY: per vertex `x y z red green blue b_r b_g b_b` (colours tone-mapped
/// sRGB bytes for viewers; `b_*` the radiosity B, exitance), per face the three indices.
pub fn write_ply(mesh: &ShadedMesh, exposure: &Exposure, mut w: impl Write) -> std::io::Result<()> {
    writeln!(
        w,
        "ply\nformat ascii 1.0\ncomment gcr radiosity solution; b_* = radiosity B (exitance)"
    )?;
    writeln!(w, "element vertex {}", mesh.positions.len())?;
    writeln!(w, "property float x\nproperty float y\nproperty float z")?;
    writeln!(
        w,
        "property uchar red\nproperty uchar green\nproperty uchar blue"
    )?;
    writeln!(
        w,
        "property float b_r\nproperty float b_g\nproperty float b_b"
    )?;
    writeln!(w, "element face {}", mesh.triangles.len())?;
    writeln!(w, "property list uchar uint vertex_indices\nend_header")?;
    for (p, b) in mesh.positions.iter().zip(&mesh.radiosity) {
        let [r, g, bl] = exposure.srgb8(*b);
        writeln!(
            w,
            "{} {} {} {r} {g} {bl} {} {} {}",
            p.x as f32, p.y as f32, p.z as f32, b[0] as f32, b[1] as f32, b[2] as f32
        )?;
    }
    for [a, b, c] in &mesh.triangles {
        writeln!(w, "3 {a} {b} {c}")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn header_counts_match_the_body() {
        let mesh = ShadedMesh {
            positions: vec![DVec3::ZERO, DVec3::X, DVec3::Y],
            triangles: vec![[0, 1, 2]],
            face_of_triangle: vec![0],
            radiosity: vec![[1.0; 3]; 3],
        };
        let mut out = Vec::new();
        write_ply(&mesh, &Exposure { scale: 1.0 }, &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        let body: Vec<&str> = text.split("end_header\n").nth(1).unwrap().lines().collect();
        assert_eq!(body.len(), 4);
        assert_eq!(body[3], "3 0 1 2");
        assert!(text.contains("element vertex 3") && text.contains("element face 1"));
    }
}
