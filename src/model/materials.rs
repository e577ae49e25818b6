//! Materials of the journal and bearing (model.md's materials table).

use serde::{Deserialize, Serialize};

/// Elastic properties of a contact body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Name from the table, or `custom` when E or ν were set directly.
    pub name: String,
    /// Young's modulus, Pa.
    pub e_pa: f64,
    /// Poisson's ratio.
    pub nu: f64,
}

/// The study's materials: (name, E in GPa, ν).
pub const MATERIALS: [(&str, f64, f64); 5] = [
    ("alloy_steel", 207.0, 0.30),
    ("stainless_steel", 193.0, 0.29),
    ("aluminium", 70.0, 0.33),
    ("copper", 117.0, 0.34),
    ("tungsten_carbide", 600.0, 0.22),
];

impl Material {
    /// Looks a material up by name (`aluminum` is accepted for `aluminium`).
    pub fn by_name(name: &str) -> Option<Self> {
        let key = match name.trim() {
            "aluminum" => "aluminium",
            n => n,
        };
        MATERIALS
            .iter()
            .find(|(n, _, _)| *n == key)
            .map(|&(n, e, nu)| Self {
                name: n.to_string(),
                e_pa: e * 1e9,
                nu,
            })
    }

    /// The names accepted by [`Material::by_name`].
    pub fn names() -> Vec<&'static str> {
        MATERIALS.iter().map(|m| m.0).collect()
    }

    /// The compliance σ = (1 − ν²)/E used by the Hertz stiffness.
    pub fn sigma(&self) -> f64 {
        (1.0 - self.nu * self.nu) / self.e_pa
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lookup() {
        let m = Material::by_name("alloy_steel").unwrap();
        assert_eq!(m.e_pa, 207e9);
        assert_eq!(m.nu, 0.30);
        assert_eq!(Material::by_name("aluminum").unwrap().name, "aluminium");
        assert!(Material::by_name("unobtainium").is_none());
        assert_eq!(Material::names().len(), 5);
    }
}
