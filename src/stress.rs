//! Plane-strain Cauchy stress with its four independent components.
//!
//! In plane strain `D_zz = 0` but `T_zz != 0`, so the stress carries `xx, yy, xy, zz`
//! (docs/model.md, conventions). Tension is positive; the pressure is `p = -tr(T)/3`.

use glam::{DMat2, DVec2};
use serde::{Deserialize, Serialize};

/// Symmetric Cauchy stress in plane strain (Pa, tension positive).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Stress {
    pub xx: f64,
    pub yy: f64,
    pub xy: f64,
    pub zz: f64,
}

impl Stress {
    pub const ZERO: Stress = Stress {
        xx: 0.0,
        yy: 0.0,
        xy: 0.0,
        zz: 0.0,
    };

    /// An isotropic state `-p 1`.
    pub fn isotropic(pressure: f64) -> Self {
        Stress {
            xx: -pressure,
            yy: -pressure,
            xy: 0.0,
            zz: -pressure,
        }
    }

    /// Pressure `p = -(T_xx + T_yy + T_zz) / 3`.
    pub fn pressure(&self) -> f64 {
        -(self.xx + self.yy + self.zz) / 3.0
    }

    /// The 3D deviator `T0 = T + p 1`.
    pub fn deviator(&self) -> Stress {
        let p = self.pressure();
        Stress {
            xx: self.xx + p,
            yy: self.yy + p,
            xy: self.xy,
            zz: self.zz + p,
        }
    }

    /// Equivalent shear stress `tau = sqrt(T0 : T0 / 2)` (the xy entry counts twice).
    pub fn equivalent_shear(&self) -> f64 {
        let d = self.deviator();
        (0.5 * (d.xx * d.xx + d.yy * d.yy + d.zz * d.zz + 2.0 * d.xy * d.xy)).sqrt()
    }

    /// Every component scaled by `k`.
    pub fn scaled(&self, k: f64) -> Stress {
        Stress {
            xx: self.xx * k,
            yy: self.yy * k,
            xy: self.xy * k,
            zz: self.zz * k,
        }
    }

    /// Traction on a plane with unit normal `n` (in-plane part).
    pub fn traction(&self, n: DVec2) -> DVec2 {
        DVec2::new(self.xx * n.x + self.xy * n.y, self.xy * n.x + self.yy * n.y)
    }

    pub fn is_finite(&self) -> bool {
        self.xx.is_finite() && self.yy.is_finite() && self.xy.is_finite() && self.zz.is_finite()
    }

    /// Trial hypoelastic update with the Jaumann rate (docs/model.md §4.1, step 1):
    /// `T* = T + dt (2G D0 + K tr(D) 1 + W T - T W)` with `D_zz = 0`.
    /// `l` is the velocity gradient `L_ab = d v_a / d x_b` (glam is column-major:
    /// `l.col(b)[a]`).
    pub fn jaumann_elastic_trial(&self, l: DMat2, dt: f64, shear: f64, bulk: f64) -> Stress {
        let dxx = l.x_axis.x;
        let dyy = l.y_axis.y;
        let dxy = 0.5 * (l.y_axis.x + l.x_axis.y);
        // Spin W_xy = (L_xy - L_yx)/2; W_yx = -W_xy.
        let w = 0.5 * (l.y_axis.x - l.x_axis.y);
        let tr = dxx + dyy;
        let lame = bulk - 2.0 * shear / 3.0;
        // (W T - T W) for symmetric T in 2D: xx: 2 w T_xy, yy: -2 w T_xy, xy: w (T_yy - T_xx).
        Stress {
            xx: self.xx + dt * (2.0 * shear * dxx + lame * tr + 2.0 * w * self.xy),
            yy: self.yy + dt * (2.0 * shear * dyy + lame * tr - 2.0 * w * self.xy),
            xy: self.xy + dt * (2.0 * shear * dxy + w * (self.yy - self.xx)),
            zz: self.zz + dt * lame * tr,
        }
    }
}

impl std::ops::Add for Stress {
    type Output = Stress;
    fn add(self, o: Stress) -> Stress {
        Stress {
            xx: self.xx + o.xx,
            yy: self.yy + o.yy,
            xy: self.xy + o.xy,
            zz: self.zz + o.zz,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invariants_of_a_known_state() {
        let t = Stress {
            xx: -3.0,
            yy: -1.0,
            xy: 1.0,
            zz: -2.0,
        };
        assert!((t.pressure() - 2.0).abs() < 1e-15);
        // deviator (-1, 1, 1, 0): tau = sqrt((1 + 1 + 0 + 2)/2) = sqrt(2)
        assert!((t.equivalent_shear() - 2f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn uniaxial_plane_strain_compression_matches_lame() {
        // D = diag(-r, 0): T_xx = (K + 4G/3)(-r dt), T_yy = T_zz = (K - 2G/3)(-r dt).
        let (g, k, r, dt) = (3.0e6, 10.0e6, 2.0, 1e-3);
        let l = DMat2::from_cols(DVec2::new(-r, 0.0), DVec2::ZERO);
        let t = Stress::ZERO.jaumann_elastic_trial(l, dt, g, k);
        assert!((t.xx - (k + 4.0 * g / 3.0) * (-r * dt)).abs() < 1e-6);
        assert!((t.yy - (k - 2.0 * g / 3.0) * (-r * dt)).abs() < 1e-6);
        assert!((t.zz - t.yy).abs() < 1e-9);
        assert_eq!(t.xy, 0.0);
    }

    #[test]
    fn rigid_spin_rotates_the_stress() {
        // v = omega x r: L = [[0, -w], [w, 0]]; an anticlockwise rotation by angle w dt.
        let omega = 0.7;
        let dt = 1e-4;
        let l = DMat2::from_cols(DVec2::new(0.0, omega), DVec2::new(-omega, 0.0));
        let mut t = Stress {
            xx: -5.0,
            yy: -1.0,
            xy: 0.0,
            zz: -2.0,
        };
        let n = 10_000;
        for _ in 0..n {
            t = t.jaumann_elastic_trial(l, dt, 1.0, 1.0);
        }
        // After rotating by theta, T_xx = -5 cos^2 - 1 sin^2, T_xy = (-5 + 1) sin cos ... with sign
        // of an anticlockwise rotation R T R^T: T_xy = (T_xx0 - T_yy0) sin cos.
        let th = omega * dt * n as f64;
        let (s, c) = th.sin_cos();
        assert!((t.xx - (-5.0 * c * c - s * s)).abs() < 1e-3);
        assert!((t.xy - (-4.0 * s * c)).abs() < 1e-3);
        assert!((t.pressure() - 8.0 / 3.0).abs() < 1e-3);
    }
}
