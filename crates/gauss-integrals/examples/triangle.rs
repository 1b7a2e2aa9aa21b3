//! Integrates a Gaussian over a triangle three ways: closed form, cubature, whole plane.

fn main() {
    let t = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 1.5, 0.0]];
    let (c, a) = ([0.4, 0.3, 0.2], 3.0);
    let exact = gauss_integrals::triangle(c, a, t[0], t[1], t[2]);
    let cub = gauss_integrals::triangle_cubature(
        |x| (-a * ((x[0] - c[0]).powi(2) + (x[1] - c[1]).powi(2) + (x[2] - c[2]).powi(2))).exp(),
        t,
        1e-13,
    );
    println!("closed form {exact:.15}");
    println!(
        "cubature    {:.15} (± {:.1e}, {} evaluations)",
        cub.value, cub.error, cub.evaluations
    );
    println!("whole plane {:.15}", gauss_integrals::plane(a, 0.2));
}
