//! The two networks: created on a starting simplex (sec. 2.4.1), frozen into the FEM step's view
//! of them (docs/design/math.md §3: a kernel cell as its sender and receiver halves; sec. 3.2: the shading
//! network as a Gaussian base with learned normals).

use super::error::SolveError;
use crate::config::SolveConfig;
use crate::domain::Domain;
use crate::element::BANDS;
use crate::kernel_cells::KernelCells;
use crate::network::GrowingNetwork;
use crate::shading::ShadingGeometry;
use glam::DVec3;
use isgcs::{Isgcs, Params};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Creates the kernel network (n = 2·dim, k = 4 in 3-D / 2 in Flatland, m = bands) and the
/// shading network (n = dim, k = 2 / 1, m = dim: the normal), each starting from a simplex on
/// random samples of its input domain.
pub fn make_networks(domain: &Domain, config: &SolveConfig) -> Result<(Isgcs, Isgcs), SolveError> {
    let dim = domain.dim();
    let mut rng = ChaCha8Rng::seed_from_u64(config.seed ^ 0x5EED);
    let pd = domain.param_dim();
    let mut input = Vec::new();
    let k_kernel = if dim == 3 { 4 } else { 2 };
    let k_shading = dim - 1;
    let mut draw = |n: usize, rng: &mut ChaCha8Rng, receiver_only: bool| -> Vec<Vec<f64>> {
        (0..n)
            .map(|_| {
                let u: Vec<f64> = (0..pd).map(|_| rng.random::<f64>()).collect();
                domain.endpoints(&u).input(&mut input);
                // `input` is (x, y) with `dim` coordinates each.
                if receiver_only {
                    input[dim..].to_vec()
                } else {
                    input.clone()
                }
            })
            .collect()
    };
    let kernel_init = draw(k_kernel + 1, &mut rng, false);
    let shading_init = draw(k_shading + 1, &mut rng, true);
    let params = Params {
        lambda: config.lambda,
        ..Params::default()
    };
    let kernel = Isgcs::new(params, 2 * dim, domain.bands(), k_kernel, kernel_init)?;
    let shading = Isgcs::new(params, dim, dim, k_shading, shading_init)?;
    Ok((kernel, shading))
}

/// Freezes the kernel network into per-cell sender/receiver halves (docs/design/math.md §3).
pub fn freeze_kernel(net: &impl GrowingNetwork, dim: usize, bands: usize) -> KernelCells {
    let n = net.cell_count();
    let mut k = KernelCells::default();
    for i in 0..n {
        let c = net.centre(i);
        let mut wx = DVec3::ZERO;
        let mut wy = DVec3::ZERO;
        for a in 0..dim {
            wx[a] = c[a];
            wy[a] = c[dim + a];
        }
        k.wx.push(wx);
        k.wy.push(wy);
        k.width.push(net.width(i));
        let o = net.output(i);
        let mut v = [0.0; BANDS];
        for b in 0..BANDS {
            v[b] = o[b.min(bands - 1)];
        }
        k.v.push(v);
    }
    k
}

/// The shading network frozen for a FEM step, or an empty geometry when nothing downstream
/// reads the base ([`SolveConfig::needs_base`]): the FEM step then costs nothing.
pub(super) fn freeze_base_geometry(
    net: &impl GrowingNetwork,
    domain: &Domain,
    config: &SolveConfig,
    base_used: bool,
) -> ShadingGeometry {
    if base_used {
        freeze_shading(net, domain, config)
    } else {
        ShadingGeometry::new(
            Vec::new(),
            Vec::new(),
            Vec::new(),
            domain.dim() - 1,
            &[],
            config.breaking,
            |_, _, _| false,
        )
    }
}

/// Freezes the shading network (cells, widths, learned normals, simplices) into the FEM's view.
pub fn freeze_shading(
    net: &impl GrowingNetwork,
    domain: &Domain,
    config: &SolveConfig,
) -> ShadingGeometry {
    let dim = domain.dim();
    let n = net.cell_count();
    let mut centres = Vec::with_capacity(n);
    let mut widths = Vec::with_capacity(n);
    let mut normals = Vec::with_capacity(n);
    let mut out = vec![0.0; dim];
    for i in 0..n {
        // The learned normal at a cell is the network's output Ψ(ŵ_i) there, not the cell's
        // weight v_i: the Gaussians overlap, so the weights of a smooth field oscillate.
        let c = net.centre(i);
        net.predict(c, &mut out);
        let mut p = DVec3::ZERO;
        let mut nrm = DVec3::ZERO;
        for a in 0..dim {
            p[a] = c[a];
            nrm[a] = out[a];
        }
        centres.push(p);
        widths.push(net.width(i));
        normals.push(nrm);
    }
    let tol = 2e-3 * domain.diagonal();
    ShadingGeometry::new(
        centres,
        widths,
        normals,
        dim - 1,
        &net.simplices(),
        config.breaking,
        |a, b, nrm| domain.spans_gap(a, b, nrm, tol),
    )
}
