//! `scene.toml`: what the experimenter knows about a folder of photographs.
//!
//! Every key is optional. Top-level keys are defaults for the whole folder; a table
//! `[images."shot_007.png"]` overrides them for one image (a folder may mix materials, cameras
//! and exposures). Keys:
//!
//! | key | type | meaning |
//! |---|---|---|
//! | `ball_diameter_mm` | number > 0 | ball diameter |
//! | `px_per_mm` | number > 0 | image scale at cloth level, as read from a ruler lying on the cloth. Ball centres sit `R` above the cloth, so balls look a few per cent larger than this scale says |
//! | `exposure_s` | number > 0 | exposure time |
//! | `material` | string | material label (`billiard`, `steel`, `rubber`, or any name) |
//! | `background` | string | file name (same folder) of a plate of the empty table in the same light |
//! | `spin` | number | known cue-ball spin `r = R omega / v` at impact |
//! | `english` | number | known cue-ball sidespin `s = R omega_z / v` at impact |
//!
//! Unknown keys are errors (a misspelt key must not be silently ignored); every error names the
//! key and, for per-image tables, the image.

use std::collections::BTreeMap;
use std::path::Path;

/// File name of the scene description inside a folder of photographs.
pub const SCENE_FILE: &str = "scene.toml";

/// Keys a scene table may contain.
pub const KEYS: [&str; 7] = [
    "ball_diameter_mm",
    "px_per_mm",
    "exposure_s",
    "material",
    "background",
    "spin",
    "english",
];

/// Values of one scene table (top level or one image); `None` where the key is absent.
/// After [`SceneConfig::for_image`], the resolved values for one image.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ImageScene {
    pub ball_diameter_mm: Option<f64>,
    pub px_per_mm: Option<f64>,
    pub exposure_s: Option<f64>,
    pub material: Option<String>,
    pub background: Option<String>,
    pub spin: Option<f64>,
    pub english: Option<f64>,
}

impl ImageScene {
    /// `self` with every key that `over` sets replaced by `over`'s value.
    pub fn overridden_by(&self, over: &ImageScene) -> ImageScene {
        ImageScene {
            ball_diameter_mm: over.ball_diameter_mm.or(self.ball_diameter_mm),
            px_per_mm: over.px_per_mm.or(self.px_per_mm),
            exposure_s: over.exposure_s.or(self.exposure_s),
            material: over.material.clone().or_else(|| self.material.clone()),
            background: over.background.clone().or_else(|| self.background.clone()),
            spin: over.spin.or(self.spin),
            english: over.english.or(self.english),
        }
    }

    pub fn is_empty(&self) -> bool {
        *self == ImageScene::default()
    }

    /// Ball radius in pixels at cloth scale, if both diameter and scale are known.
    pub fn ball_radius_px_cloth(&self) -> Option<f64> {
        Some(0.5 * self.ball_diameter_mm? * self.px_per_mm?)
    }

    fn from_table(table: &toml::Table, ctx: &str) -> Result<ImageScene, String> {
        let mut out = ImageScene::default();
        for (key, value) in table {
            let at = format!("{ctx}{key}");
            match key.as_str() {
                "ball_diameter_mm" => out.ball_diameter_mm = Some(positive(value, &at)?),
                "px_per_mm" => out.px_per_mm = Some(positive(value, &at)?),
                "exposure_s" => out.exposure_s = Some(positive(value, &at)?),
                "material" => out.material = Some(non_empty_string(value, &at)?),
                "background" => out.background = Some(non_empty_string(value, &at)?),
                "spin" => out.spin = Some(finite(value, &at)?),
                "english" => out.english = Some(finite(value, &at)?),
                _ => {
                    return Err(format!(
                        "scene.toml: unknown key '{at}' (allowed: {}, and [images.\"FILE\"] tables)",
                        KEYS.join(", ")
                    ));
                }
            }
        }
        Ok(out)
    }

    fn to_table(&self) -> toml::Table {
        let mut t = toml::Table::new();
        let mut num = |k: &str, v: Option<f64>| {
            if let Some(v) = v {
                t.insert(k.to_string(), toml::Value::Float(v));
            }
        };
        num("ball_diameter_mm", self.ball_diameter_mm);
        num("px_per_mm", self.px_per_mm);
        num("exposure_s", self.exposure_s);
        num("spin", self.spin);
        num("english", self.english);
        if let Some(m) = &self.material {
            t.insert("material".into(), toml::Value::String(m.clone()));
        }
        if let Some(b) = &self.background {
            t.insert("background".into(), toml::Value::String(b.clone()));
        }
        t
    }
}

fn number(value: &toml::Value, at: &str) -> Result<f64, String> {
    match value {
        toml::Value::Float(f) => Ok(*f),
        toml::Value::Integer(i) => Ok(*i as f64),
        other => Err(format!(
            "scene.toml: key '{at}' must be a number, found {} ({other})",
            other.type_str()
        )),
    }
}

fn finite(value: &toml::Value, at: &str) -> Result<f64, String> {
    let v = number(value, at)?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("scene.toml: key '{at}' must be finite, found {v}"))
    }
}

fn positive(value: &toml::Value, at: &str) -> Result<f64, String> {
    let v = finite(value, at)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!(
            "scene.toml: key '{at}' must be positive, found {v}"
        ))
    }
}

fn non_empty_string(value: &toml::Value, at: &str) -> Result<String, String> {
    match value {
        toml::Value::String(s) if !s.trim().is_empty() => Ok(s.clone()),
        toml::Value::String(_) => Err(format!("scene.toml: key '{at}' must not be empty")),
        other => Err(format!(
            "scene.toml: key '{at}' must be a string, found {} ({other})",
            other.type_str()
        )),
    }
}

/// A parsed `scene.toml`: folder defaults and per-image overrides.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SceneConfig {
    pub defaults: ImageScene,
    /// Per-image overrides, keyed by file name (no directory).
    pub images: BTreeMap<String, ImageScene>,
}

impl SceneConfig {
    /// Reads `dir/scene.toml`; a folder without one gives an empty configuration (every key is
    /// optional). Errors name the key and the problem.
    pub fn load(dir: &Path) -> Result<SceneConfig, String> {
        let path = dir.join(SCENE_FILE);
        if !path.exists() {
            return Ok(SceneConfig::default());
        }
        let text = std::fs::read_to_string(&path)
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        Self::parse(&text)
    }

    /// Parses the text of a `scene.toml`.
    pub fn parse(text: &str) -> Result<SceneConfig, String> {
        let root: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| format!("scene.toml: not valid TOML: {e}"))?;
        let mut top = root.clone();
        let images_value = top.remove("images");
        let defaults = ImageScene::from_table(&top, "")?;
        let mut images = BTreeMap::new();
        if let Some(v) = images_value {
            let toml::Value::Table(t) = v else {
                return Err(format!(
                    "scene.toml: key 'images' must be a table of [images.\"FILE\"] tables, found {}",
                    v.type_str()
                ));
            };
            for (file, entry) in t {
                let toml::Value::Table(et) = entry else {
                    return Err(format!(
                        "scene.toml: key 'images.\"{file}\"' must be a table, found {}",
                        entry.type_str()
                    ));
                };
                let scene = ImageScene::from_table(&et, &format!("images.\"{file}\"."))?;
                images.insert(file, scene);
            }
        }
        Ok(SceneConfig { defaults, images })
    }

    /// Resolved values for one image: its overrides on top of the folder defaults.
    pub fn for_image(&self, file_name: &str) -> ImageScene {
        match self.images.get(file_name) {
            Some(over) => self.defaults.overridden_by(over),
            None => self.defaults.clone(),
        }
    }

    /// TOML text of this configuration (parses back to an equal value).
    pub fn to_toml_string(&self) -> String {
        let mut root = self.defaults.to_table();
        let mut images = toml::Table::new();
        for (file, scene) in &self.images {
            if !scene.is_empty() {
                images.insert(file.clone(), toml::Value::Table(scene.to_table()));
            }
        }
        if !images.is_empty() {
            root.insert("images".into(), toml::Value::Table(images));
        }
        toml::to_string(&root).expect("a table of numbers and strings serialises")
    }

    /// Builds the most compact configuration that resolves to `per_image` for every image:
    /// for each key, the most common value becomes the folder default and the others become
    /// per-image overrides.
    pub fn from_images(per_image: &[(String, ImageScene)]) -> SceneConfig {
        fn mode<T: Clone + PartialEq>(vals: &[Option<T>]) -> Option<T> {
            let mut best: Option<(usize, &Option<T>)> = None;
            for v in vals {
                let n = vals.iter().filter(|w| *w == v).count();
                if best.is_none_or(|(bn, _)| n > bn) {
                    best = Some((n, v));
                }
            }
            best.and_then(|(_, v)| v.clone())
        }
        let col = |f: &dyn Fn(&ImageScene) -> Option<f64>| -> Vec<Option<u64>> {
            per_image
                .iter()
                .map(|(_, s)| f(s).map(f64::to_bits))
                .collect()
        };
        let from_bits = |b: Option<u64>| b.map(f64::from_bits);
        let strs = |f: &dyn Fn(&ImageScene) -> Option<String>| -> Vec<Option<String>> {
            per_image.iter().map(|(_, s)| f(s)).collect()
        };
        let defaults = ImageScene {
            ball_diameter_mm: from_bits(mode(&col(&|s| s.ball_diameter_mm))),
            px_per_mm: from_bits(mode(&col(&|s| s.px_per_mm))),
            exposure_s: from_bits(mode(&col(&|s| s.exposure_s))),
            material: mode(&strs(&|s| s.material.clone())),
            background: mode(&strs(&|s| s.background.clone())),
            spin: from_bits(mode(&col(&|s| s.spin))),
            english: from_bits(mode(&col(&|s| s.english))),
        };
        let mut images = BTreeMap::new();
        for (file, s) in per_image {
            let diff = |a: Option<f64>, d: Option<f64>| {
                if a.map(f64::to_bits) == d.map(f64::to_bits) {
                    None
                } else {
                    a
                }
            };
            let diff_s = |a: &Option<String>, d: &Option<String>| {
                if a == d { None } else { a.clone() }
            };
            let over = ImageScene {
                ball_diameter_mm: diff(s.ball_diameter_mm, defaults.ball_diameter_mm),
                px_per_mm: diff(s.px_per_mm, defaults.px_per_mm),
                exposure_s: diff(s.exposure_s, defaults.exposure_s),
                material: diff_s(&s.material, &defaults.material),
                background: diff_s(&s.background, &defaults.background),
                spin: diff(s.spin, defaults.spin),
                english: diff(s.english, defaults.english),
            };
            if !over.is_empty() {
                images.insert(file.clone(), over);
            }
        }
        SceneConfig { defaults, images }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn per_image_overrides_defaults() {
        let c = SceneConfig::parse(
            "ball_diameter_mm = 57.15\npx_per_mm = 3.5\nmaterial = \"billiard\"\n\
             [images.\"shot_002.png\"]\nmaterial = \"steel\"\nball_diameter_mm = 25\n",
        )
        .unwrap();
        let a = c.for_image("shot_001.png");
        assert_eq!(a.material.as_deref(), Some("billiard"));
        assert_eq!(a.ball_diameter_mm, Some(57.15));
        let b = c.for_image("shot_002.png");
        assert_eq!(b.material.as_deref(), Some("steel"));
        assert_eq!(b.ball_diameter_mm, Some(25.0));
        assert_eq!(b.px_per_mm, Some(3.5));
        assert_eq!(b.exposure_s, None);
    }

    #[test]
    fn errors_name_the_key() {
        let e = SceneConfig::parse("px_per_mm = \"big\"").unwrap_err();
        assert!(e.contains("'px_per_mm'") && e.contains("number"), "{e}");
        let e = SceneConfig::parse("[images.\"a.png\"]\nexposure_s = -1.0").unwrap_err();
        assert!(
            e.contains("images.\"a.png\".exposure_s") && e.contains("positive"),
            "{e}"
        );
        let e = SceneConfig::parse("px_per_mmm = 3.0").unwrap_err();
        assert!(e.contains("unknown key 'px_per_mmm'"), "{e}");
        let e = SceneConfig::parse("images = 3").unwrap_err();
        assert!(e.contains("'images'"), "{e}");
    }
}
