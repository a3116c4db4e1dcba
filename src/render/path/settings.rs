//! The path tracer's settings, apart from the scene it renders (as Mitsuba keeps the integrator
//! and the sampler apart from the scene): samples per pixel, a time budget, the sun-lobe walk's
//! steps and the seed. A scene file may carry them as top-level keys beside the scene; the
//! command line overrides them.

use super::sun_lobe::MAX_STEPS;
use anyhow::{ensure, Context, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// How the path tracer renders a scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Settings {
    /// Samples (camera paths) per pixel (default 64); with a time budget, the most a pass
    /// takes.
    pub spp: u32,
    /// Wall-clock cap (s): a first pass of 2 samples per pixel, then passes of a tenth of the
    /// budget (at most `spp`) until it is spent, the last one cut by rows (render.json gives
    /// the samples per pixel reached).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_budget_s: Option<f64>,
    /// Steps of the sun-lobe walk launched at every collision (docs/render.md): an unbiased
    /// variance reduction for forward-peaked phase functions; 0 is plain next-event
    /// estimation.
    pub sun_lobe_steps: usize,
    /// Seed of every random stream.
    pub seed: u64,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            spp: 64,
            time_budget_s: None,
            sun_lobe_steps: 16,
            seed: 0,
        }
    }
}

impl Settings {
    /// The settings a scene file's JSON carries beside the scene (the defaults where it has
    /// none); the scene's own keys are left to [`crate::render::scene::Scene::parse`].
    pub fn parse(text: &str) -> Result<Self> {
        let s: Settings = serde_json::from_str(text)?;
        s.validate()?;
        Ok(s)
    }

    /// [`Settings::parse`] of a scene file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read scene '{}'", path.display()))?;
        Self::parse(&text).with_context(|| format!("scene '{}'", path.display()))
    }

    /// Checks every value, naming the first bad one.
    pub fn validate(&self) -> Result<()> {
        ensure!((1..=1 << 20).contains(&self.spp), "spp must be 1…1048576");
        if let Some(b) = self.time_budget_s {
            ensure!(
                b > 0.0 && b.is_finite(),
                "time_budget_s must be a positive number of seconds"
            );
        }
        ensure!(
            self.sun_lobe_steps <= MAX_STEPS,
            "sun_lobe_steps must be 0…{MAX_STEPS} (it is {})",
            self.sun_lobe_steps
        );
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::scene::RENDERER_KEYS;

    /// The keys the scene leaves to its renderer are these settings, all of them.
    #[test]
    fn the_scene_leaves_exactly_these_keys() {
        let s = Settings {
            time_budget_s: Some(1.0),
            ..Settings::default()
        };
        let v = serde_json::to_value(&s).unwrap();
        let mut keys: Vec<&str> = v.as_object().unwrap().keys().map(|k| k.as_str()).collect();
        let mut want = RENDERER_KEYS.to_vec();
        keys.sort_unstable();
        want.sort_unstable();
        assert_eq!(keys, want);
    }

    #[test]
    fn a_scene_file_gives_its_settings_and_defaults() {
        let s = Settings::parse(r#"{"sigma_t": 0.1, "spp": 8, "seed": 3}"#).unwrap();
        assert_eq!((s.spp, s.seed, s.sun_lobe_steps), (8, 3, 16));
        let e = Settings::parse(r#"{"sun_lobe_steps": 40}"#).unwrap_err();
        assert!(
            format!("{e:#}").contains("sun_lobe_steps must be 0…32"),
            "{e:#}"
        );
        let e = Settings::parse(r#"{"spp": "many"}"#).unwrap_err();
        assert!(format!("{e:#}").contains("line 1"), "{e:#}");
    }
}
