//! Sky portals: the openings (windows, skylights, an atrium's roof) through which an interior sees
//! the sky, marked by the user as parallelograms. A sky with portals draws most of its shadow
//! rays through them (Bitterli et al. 2015's portal idea, by area sampling: a point uniform on a
//! portal chosen in proportion to the solid angle it roughly subtends, then the direction to it),
//! so that a point deep in a room does not spend its rays on the sky it cannot see. The
//! direction's solid-angle density is p_A·r²/|cos θ_portal| summed over the portals its ray
//! crosses; the sky mixes it with its hemisphere sampling ([`super::Sky`]), so directions that no
//! portal covers are still sampled and the estimate stays unbiased.

use glam::DVec3;

/// A parallelogram portal: corner `origin`, edges `e1` and `e2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Portal {
    origin: DVec3,
    e1: DVec3,
    e2: DVec3,
    /// Unit normal (e1 × e2).
    normal: DVec3,
    area: f64,
}

impl Portal {
    /// The parallelogram of the four corners `c` in order around it; `None` unless they are
    /// finite, span an area, and c0 + c2 = c1 + c3 within 10⁻⁶ of the size (a parallelogram: a
    /// rectangular window is one).
    pub fn new(c: [DVec3; 4]) -> Option<Self> {
        if !c.iter().all(|p| p.is_finite()) {
            return None;
        }
        let (e1, e2) = (c[1] - c[0], c[3] - c[0]);
        let cross = e1.cross(e2);
        let area = cross.length();
        let size = e1.length().max(e2.length());
        if area <= 1e-12 * size * size || (c[0] + c[2] - c[1] - c[3]).length() > 1e-6 * size {
            return None;
        }
        Some(Self {
            origin: c[0],
            e1,
            e2,
            normal: cross / area,
            area,
        })
    }

    /// The portal's area.
    pub fn area(&self) -> f64 {
        self.area
    }

    fn centre(&self) -> DVec3 {
        self.origin + 0.5 * (self.e1 + self.e2)
    }

    /// A rough solid angle of the portal seen from `p` (area × |cos| / d² at its centre): the
    /// weight with which it is chosen.
    fn weight(&self, p: DVec3) -> f64 {
        let d = self.centre() - p;
        let d2 = d.length_squared();
        if d2 <= 0.0 {
            return 0.0;
        }
        let w = self.area * self.normal.dot(d).abs() / (d2 * d2.sqrt());
        if w.is_finite() { w } else { 0.0 }
    }

    /// The point at `u ∈ [0, 1)²` (uniform by area).
    fn point(&self, u: [f64; 2]) -> DVec3 {
        self.origin + u[0] * self.e1 + u[1] * self.e2
    }

    /// Where the ray p + t·dir (t > 0, unit dir) crosses the portal: the squared distance and
    /// |cos θ| there; `None` when it misses.
    fn crossing(&self, p: DVec3, dir: DVec3) -> Option<(f64, f64)> {
        let denom = self.normal.dot(dir);
        if denom == 0.0 {
            return None;
        }
        let t = self.normal.dot(self.origin - p) / denom;
        if !(t > 0.0 && t.is_finite()) {
            return None;
        }
        let q = p + t * dir - self.origin;
        // coordinates along e1, e2 (the parallelogram's dual basis)
        let (a, b, c) = (
            self.e1.dot(self.e1),
            self.e1.dot(self.e2),
            self.e2.dot(self.e2),
        );
        let (qa, qb) = (q.dot(self.e1), q.dot(self.e2));
        let det = a * c - b * b;
        let (s, r) = ((qa * c - qb * b) / det, (qb * a - qa * b) / det);
        ((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&r)).then_some((t * t, denom.abs()))
    }
}

/// A set of portals and the choice among them from a receiver.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Portals(Vec<Portal>);

impl Portals {
    /// The portals.
    pub fn new(portals: Vec<Portal>) -> Self {
        Self(portals)
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The total area.
    pub fn area(&self) -> f64 {
        self.0.iter().map(Portal::area).sum()
    }

    /// Whether some portal has a selection weight from `p` (none without portals).
    pub fn in_view(&self, p: DVec3) -> bool {
        self.weights(p).1 > 0.0
    }

    /// The share of an infinite light's shadow rays drawn through the portals at `p`: 3/4 where
    /// some portal is in view (the rest by the light's own sampling, so that directions no portal
    /// covers keep a positive density), else 0.
    pub fn share(&self, p: DVec3) -> f64 {
        if self.in_view(p) { 0.75 } else { 0.0 }
    }

    /// The density of `dir` at `p` of an infinite light that draws [`Portals::share`] of its rays
    /// through the portals and the rest by its own density `own` (of the same direction).
    pub fn mix_pdf(&self, p: DVec3, dir: DVec3, own: f64) -> f64 {
        match self.share(p) {
            b if b > 0.0 => b * self.pdf(p, dir) + (1.0 - b) * own,
            _ => own,
        }
    }

    /// A direction of the mixture of [`Portals::mix_pdf`] from `u ∈ [0, 1)²`: through a portal
    /// when u\[0\] falls in the portals' share (remapped within it), else by `own` with u\[0\]
    /// remapped to [0, 1).
    pub fn mix_sample(
        &self,
        p: DVec3,
        u: [f64; 2],
        own: impl FnOnce([f64; 2]) -> DVec3,
    ) -> Option<DVec3> {
        let b = self.share(p);
        if u[0] < b {
            self.sample(p, [u[0] / b, u[1]])
        } else {
            let u0 = ((u[0] - b) / (1.0 - b)).min(1.0 - f64::EPSILON);
            Some(own([u0, u[1]]))
        }
    }

    /// The area an infinite light's power is counted over ([`super::Light::power`]): the disc of
    /// the scene's bounding radius `radius`, or with portals the flux that can come through them
    /// (at most their area, at most the disc).
    pub fn collecting_area(&self, radius: f64) -> f64 {
        let disc = std::f64::consts::PI * radius * radius;
        if self.is_empty() {
            disc
        } else {
            self.area().min(disc)
        }
    }

    /// The portals' selection weights from `p` and their sum.
    fn weights(&self, p: DVec3) -> (Vec<f64>, f64) {
        let w: Vec<f64> = self.0.iter().map(|q| q.weight(p)).collect();
        let total = w.iter().sum();
        (w, total)
    }

    /// A unit direction from `p` toward a point drawn on the portals from `u ∈ [0, 1)²` (the
    /// portal by u\[0\], which is then remapped within the portal's share to place the point with
    /// u\[1\]); `None` when no portal has weight from `p`.
    pub fn sample(&self, p: DVec3, u: [f64; 2]) -> Option<DVec3> {
        let (w, total) = self.weights(p);
        if total <= 0.0 || total.is_nan() {
            return None;
        }
        let target = u[0] * total;
        let mut before = 0.0;
        for (q, wi) in self.0.iter().zip(&w) {
            if target < before + wi || std::ptr::eq(q, self.0.last()?) {
                let v = ((target - before) / wi).clamp(0.0, 1.0 - f64::EPSILON);
                return (q.point([v, u[1]]) - p).try_normalize();
            }
            before += wi;
        }
        None
    }

    /// The solid-angle density with which [`Portals::sample`] draws the unit direction `dir`
    /// from `p`: Σ over the portals the ray crosses of P_i·(1/A_i)·r²/|cos θ_i|.
    pub fn pdf(&self, p: DVec3, dir: DVec3) -> f64 {
        let (w, total) = self.weights(p);
        if total <= 0.0 || total.is_nan() {
            return 0.0;
        }
        let mut pdf = 0.0;
        for (q, wi) in self.0.iter().zip(&w) {
            if let Some((r2, cos)) = q.crossing(p, dir) {
                pdf += wi / total / q.area * r2 / cos;
            }
        }
        if pdf.is_finite() { pdf } else { 0.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The density integrates to 1 over the directions (the portals' solid angle), and sampled
    /// directions are ones the density is positive at.
    #[test]
    fn the_portal_density_integrates_to_one() {
        let q = |x0: f64, x1: f64, y0: f64, y1: f64, z: f64| {
            Portal::new([
                DVec3::new(x0, y0, z),
                DVec3::new(x1, y0, z),
                DVec3::new(x1, y1, z),
                DVec3::new(x0, y1, z),
            ])
            .unwrap()
        };
        let portals = Portals::new(vec![
            q(-1.0, 1.0, 0.5, 1.5, 2.0),
            q(2.0, 3.0, 0.0, 2.0, 1.0),
        ]);
        let p = DVec3::new(0.3, 0.2, 0.0);
        // ∫ pdf dω over the directions (all toward +z, where the portals are)
        let integral = crate::hemisphere_quadrature(DVec3::Z, 1500, |w| portals.pdf(p, w));
        assert!((integral - 1.0).abs() < 5e-3, "{integral}");
        for k in 0..100 {
            let u = [(k as f64 + 0.5) / 100.0, 0.37];
            let d = portals.sample(p, u).unwrap();
            assert!(portals.pdf(p, d) > 0.0);
        }
        let skew = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.5), DVec3::Y];
        assert!(Portal::new(skew).is_none(), "not a parallelogram");
    }
}
