//! The analytic phase models of nephele-runtime by name and parameters (their one table is the
//! runtime's `phase::named`): what `nephele phase --model` tabulates and what a slab config or a
//! scene names as `{"kind": "runtime", "model": …, "params": {…}}`. Here they are built as the
//! toolchain holds them (boxed, f64) with the parameters used echoed as JSON.
//!
//! Names: kebab-case on the command line (`hg-draine`), snake_case in JSON (`hg_draine`); both
//! spellings are accepted everywhere, and JSON outputs write snake_case.

use anyhow::Result;
use nephele_runtime::phase::named;
pub use nephele_runtime::phase::named::{Model, Params as ModelParams, Preset};
use nephele_runtime::PhaseFunction;

/// An analytic phase function.
pub type Boxed = Box<dyn PhaseFunction<f64> + Sync>;

/// The model with these parameters, and the parameters it used as JSON (HG+Draine from a
/// diameter: its lobes, the diameter as `diameter_um` and the preset; XLF: `normalised`).
pub fn build(m: Model, p: &ModelParams) -> Result<(Boxed, serde_json::Value)> {
    let (model, used) = named::build::<f64>(m, p)?;
    let mut echo = serde_json::to_value(used)?;
    if let Some(d) = echo.as_object_mut() {
        match m {
            Model::Xlf => {
                d.insert("normalised".into(), true.into());
            }
            Model::HgDraine => {
                let diameter = d.remove("diameter").unwrap_or_default();
                d.insert("diameter_um".into(), diameter);
                d.entry("preset").or_insert(serde_json::Value::Null);
            }
            _ => {}
        }
    }
    Ok((Box::new(model), echo))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Names reach the right model in both spellings; JSON writes snake_case and refuses an
    /// unknown name, naming it.
    #[test]
    fn names_parse_in_kebab_and_snake_case_in_json() {
        for (m, name) in Model::NAMES {
            let json = serde_json::to_string(&m).unwrap();
            assert_eq!(json, format!("\"{}\"", name.replace('-', "_")));
            assert_eq!(
                serde_json::from_str::<Model>(&format!("\"{name}\"")).unwrap(),
                m
            );
        }
        let e = serde_json::from_str::<Model>("\"hg-drain\"")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("unknown model `hg-drain`") && e.contains("hg-draine"),
            "{e}"
        );
    }

    /// The echo of HG+Draine from a diameter names the diameter as configs write it.
    #[test]
    fn the_echo_keeps_the_config_names() {
        let p = ModelParams {
            diameter: Some(10.0),
            ..ModelParams::default()
        };
        let (_, echo) = build(Model::HgDraine, &p).unwrap();
        assert_eq!(echo["diameter_um"], 10.0);
        assert_eq!(echo["preset"], "jendersie_deon");
        assert!(echo["g_hg"].as_f64().is_some() && echo.get("diameter").is_none());
        let p = ModelParams {
            g_hg: Some(0.9),
            g_d: Some(0.5),
            alpha: Some(1.0),
            w_d: Some(0.1),
            ..ModelParams::default()
        };
        let (_, echo) = build(Model::HgDraine, &p).unwrap();
        assert!(echo["diameter_um"].is_null() && echo["preset"].is_null());
    }
}
