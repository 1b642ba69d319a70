//! Cloth materials: area density and the stiffness of the paper's three energies.
//!
//! The paper's energies (eq. 4–7) are scale-free; a [`Material`] gives them physical weights
//! so that a garment behaves the same at any resolution of its control mesh:
//! - `density` (kg/m²) times the rest area gives the lumped masses;
//! - `stretch` and `compression` are membrane moduli Y (N/m): each edge's E_s is weighted by
//!   Y times the area beside the edge (each face gives each of its n edges 2/n of its area), so
//!   a regular quad grid stretched by ε along a thread stores ½ Y ε² per square metre;
//! - `shear` (N/m) weights the product E_d by the quad's area (a quartic penalty, see
//!   the private `energy::shear`);
//! - `bend` is a bending modulus B (N·m): each thread triple's E_p, which is ½ θ² for a small
//!   turn θ, is weighted by B times its area over its squared length, so a curvature κ stores
//!   ½ B κ² per square metre;
//! - `damping` β (seconds) is stiffness-proportional: each edge's damper (lesson eq. 3) has
//!   k_d = β times the spring's rest stiffness along the edge;
//! - `drag` (kg/(m²·s)) is linear air drag per unit area, −drag · area · (v − wind).
//!
//! The preset numbers are order-of-magnitude values, not measurements: densities are typical
//! fabric weights (shirting cotton 150 g/m², silk 60 g/m², 12 oz denim ≈ 400 g/m², 1 mm
//! garment leather ≈ 900 g/m²); membrane moduli sit in the 10²–10⁴ N/m range that tensile tests
//! of woven fabrics report (Kawabata's KES-F; Wang, O'Brien & Ramamoorthi 2011); bending moduli
//! in the 10⁻⁶–10⁻⁴ N·m range of Kawabata's bending tests; compression is a tenth of stretch so
//! cloth buckles instead of shrinking (Choi & Ko 2002); drag gives a flat sheet a terminal
//! velocity of a few metres per second.

use crate::ClothError;

/// The physical parameters of a fabric. See the module docs for units and meaning.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Area density, kg/m².
    pub density: f64,
    /// Membrane modulus in tension, N/m.
    pub stretch: f64,
    /// Membrane modulus in compression, N/m (softer than `stretch` so cloth buckles).
    pub compression: f64,
    /// Weight of the paper's diagonal shear energy, N/m.
    pub shear: f64,
    /// Bending modulus, N·m.
    pub bend: f64,
    /// Stiffness-proportional damping along edges, seconds.
    pub damping: f64,
    /// Linear air drag per unit area, kg/(m²·s).
    pub drag: f64,
}

impl Material {
    /// Shirting cotton.
    pub const COTTON: Self = Self {
        density: 0.15,
        stretch: 2.0e3,
        compression: 2.0e2,
        shear: 1.0e3,
        bend: 5.0e-6,
        damping: 1.0e-3,
        drag: 0.3,
    };
    /// Light silk: light, soft, floppy.
    pub const SILK: Self = Self {
        density: 0.06,
        stretch: 8.0e2,
        compression: 8.0e1,
        shear: 3.0e2,
        bend: 1.0e-6,
        damping: 5.0e-4,
        drag: 0.3,
    };
    /// 12 oz denim: heavy and stiff.
    pub const DENIM: Self = Self {
        density: 0.40,
        stretch: 8.0e3,
        compression: 8.0e2,
        shear: 4.0e3,
        bend: 5.0e-5,
        damping: 2.0e-3,
        drag: 0.3,
    };
    /// 1 mm garment leather: heaviest and stiffest in bending.
    pub const LEATHER: Self = Self {
        density: 0.90,
        stretch: 5.0e3,
        compression: 5.0e2,
        shear: 5.0e3,
        bend: 2.0e-4,
        damping: 3.0e-3,
        drag: 0.3,
    };

    /// Checks that every parameter is finite, the density positive and the rest non-negative.
    ///
    /// # Errors
    /// [`ClothError::BadMaterial`] naming the first bad parameter.
    pub fn validate(&self) -> Result<(), ClothError> {
        let fields = [
            ("density", self.density, true),
            ("stretch", self.stretch, false),
            ("compression", self.compression, false),
            ("shear", self.shear, false),
            ("bend", self.bend, false),
            ("damping", self.damping, false),
            ("drag", self.drag, false),
        ];
        for (name, value, positive) in fields {
            let ok = value.is_finite() && if positive { value > 0.0 } else { value >= 0.0 };
            if !ok {
                return Err(ClothError::BadMaterial {
                    name,
                    value,
                    positive,
                });
            }
        }
        Ok(())
    }
}

impl Default for Material {
    fn default() -> Self {
        Self::COTTON
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_are_valid_and_bad_values_are_named() {
        for m in [
            Material::COTTON,
            Material::SILK,
            Material::DENIM,
            Material::LEATHER,
        ] {
            m.validate().unwrap();
        }
        let bad = Material {
            bend: -1.0,
            ..Material::COTTON
        };
        assert!(matches!(
            bad.validate(),
            Err(ClothError::BadMaterial { name: "bend", .. })
        ));
        let massless = Material {
            density: 0.0,
            ..Material::COTTON
        };
        assert!(massless.validate().is_err());
    }
}
