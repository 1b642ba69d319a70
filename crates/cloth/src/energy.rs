//! Element energies of the paper's mass-spring model, with gradients and Hessians.
//!
//! DeRose, Kass & Truong 1998, §5, write every internal force as the gradient of a small energy
//! (lesson eq. 4–5: E = ½ k C², F = −k C ∂C/∂x):
//! - stretch, eq. 4: E_s(p1, p2) = ½ (|p1 − p2| / |p1* − p2*| − 1)², on every edge;
//! - shear, eq. 5: E_d(p1, p2, p3, p4) = E_s(p1, p3) · E_s(p2, p4), on each quad's diagonals;
//! - bend, eq. 6–7: E_p = ½ [C(p1, p2, p3) − C(p1*, p2*, p3*)]² with
//!   C = |(p3 − p2)/|p3* − p2*| − (p2 − p1)/|p2* − p1*||, on triples along a thread.
//!
//! Each energy depends on the points only through one or two *difference vectors*
//! d = Σ c_a p_a (p1 − p2 for a spring, a diagonal for shear, the weighted second difference
//! for bend), so this module works in d-space: it returns the energy, its gradient and its
//! Hessian with respect to the d's, which the assembly (`crate::assemble`) maps to the points
//! by the chain rule with the constant coefficients c. Stretch and bend are both a
//! *radial spring* ½ κ (|d| − r)², whose Hessian κ [d̂ d̂ᵀ + (1 − r/|d|)(I − d̂ d̂ᵀ)] is
//! indefinite when |d| < r; shear is a product of two radial springs.
//!
//! Implicit steps need a positive semi-definite stiffness so that the system matrix stays SPD
//! and conjugate gradients converge (Baraff & Witkin 1998, §5.2, drop the negative transverse
//! term of compressed springs; "projected Newton", Teran et al. 2005, clamps each element's
//! eigenvalues at zero). With `project` set, every Hessian here is the exact eigen-clamp of
//! the d-space Hessian: for a radial spring the two eigenvalues are κ (along d) and
//! κ (1 − r/|d|) (across), and the latter is clamped; for shear the 6×6 Hessian splits into the
//! plane of the two diagonal directions (a 2×2 clamped by its eigen-decomposition) and the four
//! transverse directions (diagonal, clamped). Since the point Hessian is Bᵀ G B for the constant
//! map B from points to d's, a PSD G gives a PSD element Hessian.

use nalgebra::{Matrix2, Matrix3, Vector3};

/// A 3-vector of `f64`.
pub type Vec3 = Vector3<f64>;
/// A 3×3 matrix of `f64`.
pub type Mat3 = Matrix3<f64>;

/// An energy of `K` difference vectors with its gradient and Hessian with respect to them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Local<const K: usize> {
    /// The energy, in joules.
    pub energy: f64,
    /// ∂E/∂d_k.
    pub grad: [Vec3; K],
    /// ∂²E/∂d_k∂d_l.
    pub hess: [[Mat3; K]; K],
}

/// A radial spring ½ κ (|d| − r)² evaluated at one d.
#[derive(Clone, Copy, Debug)]
struct Radial {
    energy: f64,
    /// κ (|d| − r) d̂: the gradient.
    grad: Vec3,
    /// d̂, or zero when d is zero.
    dir: Vec3,
    /// The Hessian eigenvalue along d̂.
    along: f64,
    /// The Hessian eigenvalue across d̂ (twice repeated), κ (1 − r/|d|).
    across: f64,
}

impl Radial {
    fn new(d: &Vec3, kappa: f64, rest: f64) -> Self {
        let length = d.norm();
        let stretch = length - rest;
        if length > 0.0 {
            let dir = d / length;
            Self {
                energy: 0.5 * kappa * stretch * stretch,
                grad: dir * (kappa * stretch),
                dir,
                along: kappa,
                across: kappa * (1.0 - rest / length),
            }
        } else {
            // At d = 0 the direction is undefined: the gradient vanishes and, unless the rest
            // length is zero too (a smooth ½ κ |d|²), the transverse curvature is −∞; use 0.
            Self {
                energy: 0.5 * kappa * rest * rest,
                grad: Vec3::zeros(),
                dir: Vec3::zeros(),
                along: kappa,
                across: if rest == 0.0 { kappa } else { 0.0 },
            }
        }
    }

    /// The Hessian with eigenvalues scaled by `scale` (≥ 0), the transverse one clamped at
    /// zero when `project` is set.
    fn hess(&self, scale: f64, project: bool) -> Mat3 {
        let across = if project {
            self.across.max(0.0)
        } else {
            self.across
        };
        if self.dir == Vec3::zeros() {
            return Mat3::identity() * (scale * across);
        }
        let along = self.dir * self.dir.transpose();
        (along * self.along + (Mat3::identity() - along) * across) * scale
    }
}

/// Stretch, the paper's eq. 4 times a stiffness: k · ½ (|d|/L − 1)² with `d` = p1 − p2 and `L`
/// the rest length; `compression` replaces `stretch` as k while |d| < L, so cloth buckles
/// rather than shrinks (Choi & Ko 2002).
#[must_use]
pub fn stretch(d: &Vec3, rest: f64, stretch: f64, compression: f64, project: bool) -> Local<1> {
    let k = if d.norm() >= rest {
        stretch
    } else {
        compression
    };
    let r = Radial::new(d, k / (rest * rest), rest);
    Local {
        energy: r.energy,
        grad: [r.grad],
        hess: [[r.hess(1.0, project)]],
    }
}

/// Bend, the paper's eq. 6–7 times a stiffness: k · ½ (|e| − C*)², where `e` is the weighted
/// second difference (p3 − p2)/L23 − (p2 − p1)/L12 and C* its rest length.
#[must_use]
pub fn bend(e: &Vec3, rest: f64, k: f64, project: bool) -> Local<1> {
    let r = Radial::new(e, k, rest);
    Local {
        energy: r.energy,
        grad: [r.grad],
        hess: [[r.hess(1.0, project)]],
    }
}

/// Shear, the paper's eq. 5 times a stiffness: k · E_s(d1) · E_s(d2) on the diagonals d1, d2 of
/// a quad with rest lengths `rest[0]`, `rest[1]`.
#[must_use]
pub fn shear(d1: &Vec3, d2: &Vec3, rest: [f64; 2], k: f64, project: bool) -> Local<2> {
    let a = Radial::new(d1, 1.0 / (rest[0] * rest[0]), rest[0]);
    let b = Radial::new(d2, 1.0 / (rest[1] * rest[1]), rest[1]);
    let grad = [a.grad * (k * b.energy), b.grad * (k * a.energy)];
    let energy = k * a.energy * b.energy;
    let cross = a.grad * b.grad.transpose() * k;
    if !project {
        return Local {
            energy,
            grad,
            hess: [
                [a.hess(k * b.energy, false), cross],
                [cross.transpose(), b.hess(k * a.energy, false)],
            ],
        };
    }
    // The plane spanned by (â, 0) and (0, b̂): a 2×2 block, clamped by eigen-decomposition.
    let ga = a.grad.dot(&a.dir);
    let gb = b.grad.dot(&b.dir);
    let plane = Matrix2::new(
        k * b.energy * a.along,
        k * ga * gb,
        k * ga * gb,
        k * a.energy * b.along,
    );
    let eig = plane.symmetric_eigen();
    let clamped = eig.eigenvectors
        * Matrix2::from_diagonal(&eig.eigenvalues.map(|l| l.max(0.0)))
        * eig.eigenvectors.transpose();
    let transverse = |r: &Radial, scale: f64| {
        let p = r.dir * r.dir.transpose();
        (Mat3::identity() - p) * (scale * r.across.max(0.0))
    };
    let h11 = a.dir * a.dir.transpose() * clamped[(0, 0)] + transverse(&a, k * b.energy);
    let h22 = b.dir * b.dir.transpose() * clamped[(1, 1)] + transverse(&b, k * a.energy);
    let h12 = a.dir * b.dir.transpose() * clamped[(0, 1)];
    Local {
        energy,
        grad,
        hess: [[h11, h12], [h12.transpose(), h22]],
    }
}

#[cfg(test)]
mod tests {
    //! Finite-difference checks of every energy's gradient and Hessian, and PSD projection.
    use super::*;
    use crate::testing::Rng;

    /// Central differences of `f` along each coordinate of each d.
    fn check<const K: usize>(d: [Vec3; K], f: impl Fn(&[Vec3; K]) -> Local<K>) {
        let eps = 1e-6;
        let at = f(&d);
        let scale_g: f64 = at.grad.iter().map(|g| g.norm()).sum::<f64>().max(1e-12);
        let scale_h: f64 = at
            .hess
            .iter()
            .flatten()
            .map(|h| h.norm())
            .sum::<f64>()
            .max(1e-12);
        for k in 0..K {
            for c in 0..3 {
                let (mut plus, mut minus) = (d, d);
                plus[k][c] += eps;
                minus[k][c] -= eps;
                let (fp, fm) = (f(&plus), f(&minus));
                let fd = (fp.energy - fm.energy) / (2.0 * eps);
                assert!(
                    (fd - at.grad[k][c]).abs() < 1e-6 * scale_g,
                    "gradient d{k}[{c}]: fd {fd} vs {}",
                    at.grad[k][c]
                );
                for l in 0..K {
                    let fd = (fp.grad[l] - fm.grad[l]) / (2.0 * eps);
                    let exact = at.hess[l][k].column(c);
                    assert!(
                        (fd - exact).norm() < 1e-6 * scale_h,
                        "hessian d{l}/d{k}[{c}]: fd {fd} vs {exact}"
                    );
                }
            }
        }
    }

    fn min_eigenvalue<const K: usize>(local: &Local<K>) -> f64 {
        let n = 3 * K;
        let m = nalgebra::DMatrix::from_fn(n, n, |i, j| local.hess[i / 3][j / 3][(i % 3, j % 3)]);
        m.symmetric_eigenvalues().min()
    }

    #[test]
    fn stretch_derivatives_match_finite_differences() {
        let mut rng = Rng::new(1);
        for _ in 0..50 {
            let d = rng.vec3();
            let rest = d.norm() * rng.range(0.5, 1.5);
            check([d], |d| stretch(&d[0], rest, 7.0, 7.0, false));
        }
    }

    #[test]
    fn bend_derivatives_match_finite_differences() {
        let mut rng = Rng::new(2);
        for _ in 0..50 {
            let e = rng.vec3();
            let rest = e.norm() * rng.range(0.0, 2.0);
            check([e], |e| bend(&e[0], rest, 3.0, false));
        }
    }

    #[test]
    fn shear_derivatives_match_finite_differences() {
        let mut rng = Rng::new(3);
        for _ in 0..50 {
            let (d1, d2) = (rng.vec3(), rng.vec3());
            let rest = [
                d1.norm() * rng.range(0.5, 1.5),
                d2.norm() * rng.range(0.5, 1.5),
            ];
            check([d1, d2], |d| shear(&d[0], &d[1], rest, 5.0, false));
        }
    }

    #[test]
    fn projected_hessians_are_psd_and_exact_when_convex() {
        let mut rng = Rng::new(4);
        for _ in 0..50 {
            let (d1, d2) = (rng.vec3(), rng.vec3());
            let rest = [
                d1.norm() * rng.range(0.5, 1.5),
                d2.norm() * rng.range(0.5, 1.5),
            ];
            let s = shear(&d1, &d2, rest, 5.0, true);
            assert!(min_eigenvalue(&s) > -1e-9);
            let raw = shear(&d1, &d2, rest, 5.0, false);
            if min_eigenvalue(&raw) >= 0.0 {
                for (p, r) in s.hess.iter().flatten().zip(raw.hess.iter().flatten()) {
                    assert!((p - r).norm() < 1e-9 * (1.0 + r.norm()));
                }
            }
            assert!(min_eigenvalue(&stretch(&d1, rest[0], 2.0, 1.0, true)) > -1e-12);
            assert!(min_eigenvalue(&bend(&d1, rest[0], 2.0, true)) > -1e-12);
        }
    }

    #[test]
    fn compression_uses_the_softer_stiffness() {
        let d = Vec3::new(0.5, 0.0, 0.0);
        let soft = stretch(&d, 1.0, 100.0, 1.0, false);
        assert!((soft.energy - 0.5 * 0.25).abs() < 1e-15);
        let long = stretch(&(d * 3.0), 1.0, 100.0, 1.0, false);
        assert!((long.energy - 100.0 * 0.5 * 0.25).abs() < 1e-12);
    }
}
