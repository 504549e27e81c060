//! Material presets (`datasets/materials.toml`): the paper's Table 1 coefficients, ball size and
//! mass, cloth friction, and ball colours. Loaded at run time so the numbers live in one data file.

use crate::physics::Coefficients;
use crate::physics::path::Cloth;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One material preset.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    pub label: String,
    pub e: f64,
    pub mu: f64,
    pub mu_static: f64,
    pub mu_table: f64,
    pub diameter_mm: f64,
    pub mass_g: f64,
    pub cloth_mu_slide: f64,
    pub cloth_mu_roll: f64,
    pub cue_rgb: [f64; 3],
    pub object_rgb: [f64; 3],
    pub specular: f64,
}

impl Material {
    pub fn coefficients(&self) -> Coefficients {
        Coefficients::new(self.e, self.mu, self.mu_table).with_static(self.mu_static)
    }

    pub fn cloth(&self) -> Cloth {
        Cloth {
            mu_slide: self.cloth_mu_slide,
            mu_roll: self.cloth_mu_roll,
        }
    }

    pub fn radius_m(&self) -> f64 {
        0.5e-3 * self.diameter_mm
    }
}

/// All presets, by name (`billiard`, `steel`, `rubber`).
#[derive(Debug, Clone, PartialEq)]
pub struct Materials(pub BTreeMap<String, Material>);

/// Environment variable that points to another materials file.
pub const MATERIALS_ENV: &str = "STREAKFIT_MATERIALS";

impl Materials {
    /// Where the presets are looked for: `$STREAKFIT_MATERIALS`, `./datasets/materials.toml`, then
    /// the crate's own `datasets/materials.toml`.
    pub fn default_path() -> PathBuf {
        if let Ok(p) = std::env::var(MATERIALS_ENV) {
            return PathBuf::from(p);
        }
        let local = PathBuf::from("datasets/materials.toml");
        if local.exists() {
            return local;
        }
        Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets/materials.toml")
    }

    pub fn load(path: &Path) -> Result<Materials, String> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("cannot read materials file {}: {e}", path.display()))?;
        Self::parse(&text).map_err(|e| format!("{}: {e}", path.display()))
    }

    pub fn parse(text: &str) -> Result<Materials, String> {
        let map: BTreeMap<String, Material> =
            toml::from_str(text).map_err(|e| format!("malformed materials table: {e}"))?;
        for (name, m) in &map {
            m.coefficients()
                .validate()
                .map_err(|e| format!("material '{name}': {e}"))?;
            for (k, v) in [
                ("diameter_mm", m.diameter_mm),
                ("mass_g", m.mass_g),
                ("cloth_mu_slide", m.cloth_mu_slide),
                ("cloth_mu_roll", m.cloth_mu_roll),
            ] {
                if !(v.is_finite() && v > 0.0) {
                    return Err(format!("material '{name}': {k} = {v} must be positive"));
                }
            }
        }
        Ok(Materials(map))
    }

    pub fn get(&self, name: &str) -> Result<&Material, String> {
        self.0.get(name).ok_or_else(|| {
            format!(
                "unknown material '{name}' (known: {})",
                self.0.keys().cloned().collect::<Vec<_>>().join(", ")
            )
        })
    }

    pub fn names(&self) -> Vec<String> {
        self.0.keys().cloned().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shipped_presets_hold_table_1() {
        let m = Materials::load(&Materials::default_path()).unwrap();
        let b = m.get("billiard").unwrap();
        assert_eq!((b.e, b.mu, b.mu_table), (0.97, 0.07, 0.15));
        let s = m.get("steel").unwrap();
        assert_eq!(
            (s.e, s.mu, s.mu_static, s.diameter_mm),
            (0.92, 0.14, 0.18, 25.0)
        );
        let r = m.get("rubber").unwrap();
        assert_eq!((r.e, r.mu, r.mu_table, r.mass_g), (0.88, 0.60, 0.55, 46.4));
        assert!(m.get("glass").unwrap_err().contains("glass"));
    }
}
