//! The Perez sky's luminance toward given directions, for comparing with Radiance's `gendaylit`
//! (`xtask/py/perez_vs_gendaylit.py`). Radiance's frame (`--up z`: x east, y north, z up).
//!
//! `cargo run --release -p scene-sampler --example perez_sky -- BEARING ELEVATION DN DH [EPS DELTA]
//! < directions`
//!
//! BEARING, ELEVATION: the sun (degrees; bearing from north through east); DN: its direct normal
//! illuminance, DH: the sky's diffuse horizontal illuminance (lux). Without EPS DELTA the sky is
//! the one `--sun BEARING,ELEVATION,DN --sky perez:DH --up z` gives; with them, the Perez sky of
//! those parameters normalised to DH. Reads `x y z` per line; writes the luminance (cd/m²) per
//! line, and `# epsilon delta` first.

use scene_sampler::lights::lighting::{Lighting, Up, parse_sky, parse_sun};
use scene_sampler::lights::{Sky, SkyModel};
use scene_sampler::{BANDS, Light};
use std::io::BufRead;
use std::sync::Arc;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse::<f64>())
        .collect::<Result<_, _>>()?;
    let [bearing, elevation, dn, dh] = args[..4] else {
        return Err("expected BEARING ELEVATION DN DH [EPS DELTA]".into());
    };
    let zenith = (90.0 - elevation).to_radians();
    let (epsilon, delta) = match args[4..] {
        [e, d] => (e, d),
        _ => scene_sampler::lights::perez::parameters_from_illuminance(dn, dh, zenith),
    };
    let sky: Arc<dyn Light> = if args.len() == 6 {
        let model = SkyModel::Perez {
            sun: Up::Z.direction(bearing, elevation),
            epsilon,
            delta,
        };
        let up = Up::Z.frame().0;
        Arc::new(Sky::new(model, up, [dh; BANDS], [0.0; BANDS]).ok_or("no such Perez sky")?)
    } else {
        // the whole path of the options --sun B,E,DN --sky perez:DH --up z: the sun, then the sky
        let lighting = Lighting {
            up: Up::Z,
            sun: Some(parse_sun(&format!("{bearing},{elevation},{dn}"))?),
            sky: Some(parse_sky(&format!("perez:{dh}"))?),
            ..Lighting::default()
        };
        lighting.lights()?.swap_remove(1)
    };
    eprintln!("{}", sky.describe());
    println!("# {epsilon} {delta}");
    for line in std::io::stdin().lock().lines() {
        let v: Vec<f64> = line?
            .split_whitespace()
            .map(str::parse)
            .collect::<Result<_, _>>()?;
        let w = glam::DVec3::new(v[0], v[1], v[2]).normalize();
        println!("{}", sky.escaped(w)[0] / std::f64::consts::PI);
    }
    Ok(())
}
