//! A render's folder as `compare` reads it (only the files its render.json lists), and the
//! checks that a reference and its candidates can be compared: one scene, one camera, a
//! path-traced reference with its halves.

use super::super::image::GROUP_FIRST;
use crate::io::npy::read_npy;
use anyhow::{bail, ensure, Context, Result};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// A render directory's arrays.
pub struct RenderDir {
    /// The directory.
    pub dir: PathBuf,
    /// Method ("path_tracer", "collector", ...).
    pub method: String,
    /// render.json.
    pub meta: serde_json::Value,
    /// Width and height.
    pub size: (usize, usize),
    /// [group, H, W, 3].
    pub groups: Vec<f32>,
    /// [H, W, 3].
    pub beauty: Vec<f32>,
    /// [H, W].
    pub opacity: Vec<f32>,
    /// [2, group, H, W, 3], if written.
    pub halves: Option<Vec<f32>>,
    /// [H, W], if written.
    pub regions: Option<Vec<u8>>,
}

/// Whether render.json lists `name` among the files its render wrote: a file of an earlier
/// render left in the same folder is not this render's.
pub(super) fn listed(meta: &serde_json::Value, name: &str) -> bool {
    meta["files"].get(name).is_some()
}

/// A render directory's render.json.
pub(super) fn read_meta(dir: &Path) -> Result<serde_json::Value> {
    let json = dir.join("render.json");
    let text = std::fs::read_to_string(&json)
        .with_context(|| format!("cannot read '{}' (a render directory?)", json.display()))?;
    serde_json::from_str(&text).with_context(|| format!("'{}'", json.display()))
}

/// Width and height in render.json.
pub(super) fn meta_size(meta: &serde_json::Value) -> (u64, u64) {
    let dim = |key: &str| meta[key].as_u64().unwrap_or(0);
    (dim("width"), dim("height"))
}

impl RenderDir {
    /// Reads a directory `nephele render` wrote.
    pub fn read(dir: &Path) -> Result<Self> {
        let meta = read_meta(dir)?;
        let (w, h) = meta_size(&meta);
        ensure!(
            w > 0 && h > 0,
            "'{}': no image size",
            dir.join("render.json").display()
        );
        let ng = GROUP_FIRST.len() as u64;
        let halves = dir.join("halves.npy");
        let regions = dir.join("regions.npy");
        Ok(Self {
            dir: dir.to_path_buf(),
            method: method_name(&meta),
            size: (w as usize, h as usize),
            groups: read_npy(&dir.join("groups.npy"), &[ng, h, w, 3])?,
            beauty: read_npy(&dir.join("beauty.npy"), &[h, w, 3])?,
            opacity: read_npy(&dir.join("opacity.npy"), &[h, w])?,
            halves: if listed(&meta, "halves.npy") && halves.exists() {
                Some(read_npy(&halves, &[2, ng, h, w, 3])?)
            } else {
                None
            },
            regions: if listed(&meta, "regions.npy") && regions.exists() {
                Some(read_npy(&regions, &[h, w])?)
            } else {
                None
            },
            meta,
        })
    }

    pub(super) fn pixels(&self) -> usize {
        self.size.0 * self.size.1
    }

    /// Whether its groups of orders ≥ 2 are resolved (the octaves write their sum as one).
    pub(super) fn splits_orders(&self) -> bool {
        self.method != "octaves"
    }
}

/// Refuses what cannot be compared: a reference without the path tracer's halves.npy (its
/// noise estimate), and candidates of another scene, camera or image size than the
/// reference's (from render.json, before any array is read).
pub(super) fn check_inputs(reference: &Path, candidates: &[PathBuf]) -> Result<()> {
    let r = read_meta(reference)?;
    ensure!(
        listed(&r, "halves.npy") && reference.join("halves.npy").exists(),
        "'{}' holds a {} render without halves.npy: the reference must be a path-traced render \
         (its render.json lists halves.npy); did you swap --reference and --candidate?",
        reference.display(),
        method_name(&r)
    );
    let (r_scene, r_camera) = scene_and_camera(&r, reference)?;
    for c in candidates {
        let m = read_meta(c)?;
        let (c_scene, c_camera) = scene_and_camera(&m, c)?;
        let pair = format!(
            "'{}' and the reference '{}'",
            c.display(),
            reference.display()
        );
        if let Some(d) = first_difference(&r_scene, &c_scene, "") {
            bail!("{pair} are renders of different scenes ({d}): compare renders of one scene");
        }
        if let Some(d) = first_difference(&r_camera, &c_camera, "camera") {
            bail!("{pair} are seen from different cameras ({d}): compare renders of one scene");
        }
        let ((rw, rh), (cw, ch)) = (meta_size(&r), meta_size(&m));
        ensure!(
            (rw, rh) == (cw, ch),
            "{pair} differ in image size ({cw}×{ch} against {rw}×{rh} pixels): render both at \
             one --size"
        );
    }
    Ok(())
}

/// render.json's scene without its render settings, and its camera without the image size.
pub(super) fn scene_and_camera(meta: &Value, dir: &Path) -> Result<(Value, Value)> {
    let Some(Value::Object(scene)) = meta.get("scene") else {
        bail!(
            "'{}' records no scene (written by an older nephele?): render it again",
            dir.join("render.json").display()
        );
    };
    let mut scene = scene.clone();
    // Free text: renders of one scene may describe it differently; and a render.json may keep
    // the path tracer's settings in its scene (the scene file's keys beside the scene).
    scene.remove("description");
    for key in crate::render::scene::RENDERER_KEYS {
        scene.remove(key);
    }
    let mut camera = scene.remove("camera").unwrap_or_default();
    if let Some(c) = camera.as_object_mut() {
        c.remove("width");
        c.remove("height");
    }
    Ok((Value::Object(scene), camera))
}

/// The first place where the reference's `r` and a candidate's `c` differ, as "path: c
/// against the reference's r" (a "kind" first: a slab against a cloud says so, not their
/// first field). Numbers count as equal within 1e-9 relative: one scene file echoed twice
/// gives the same bits, but one rewritten by a script need not.
pub(super) fn first_difference(r: &Value, c: &Value, path: &str) -> Option<String> {
    let at = |k: &str| match path {
        "" => k.to_string(),
        p => format!("{p}.{k}"),
    };
    match (r, c) {
        (Value::Object(x), Value::Object(y)) => {
            let mut keys: Vec<&String> = x.keys().chain(y.keys()).collect();
            keys.sort_by_key(|k| (k.as_str() != "kind", k.as_str()));
            keys.dedup();
            keys.into_iter().find_map(|k| {
                let get =
                    |o: &serde_json::Map<String, Value>| o.get(k).cloned().unwrap_or_default();
                first_difference(&get(x), &get(y), &at(k))
            })
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => x
            .iter()
            .zip(y)
            .enumerate()
            .find_map(|(i, (p, q))| first_difference(p, q, &format!("{path}[{i}]"))),
        (Value::Number(x), Value::Number(y)) => match (x.as_f64(), y.as_f64()) {
            (Some(p), Some(q)) if (p - q).abs() <= 1e-9 * p.abs().max(q.abs()) => None,
            _ => Some(format!("{path}: {c} against the reference's {r}")),
        },
        _ => (r != c).then(|| format!("{path}: {} against the reference's {}", short(c), short(r))),
    }
}

/// A JSON value for a one-line message: at most 40 characters.
pub(super) fn short(v: &Value) -> String {
    let s = v.to_string();
    match s.char_indices().nth(40) {
        Some((i, _)) => format!("{}…", &s[..i]),
        None => s,
    }
}

/// A render's method as render.json names it, with what tells two renders of one method
/// apart: the collector's finite-cloud correction ("collector (leakage)"), the octaves' a, b
/// and c ("octaves (a 0.28, b 0.96, c 0.81)").
pub(super) fn method_name(meta: &serde_json::Value) -> String {
    let method = meta["method"].as_str().unwrap_or("path_tracer");
    let details = &meta["details"];
    match method {
        "collector" => match details["correction"].as_str() {
            Some(c) => format!("{method} ({c})"),
            None => method.to_string(),
        },
        "octaves" => {
            let o = &details["options"]["octaves"];
            match (o["a"].as_f64(), o["b"].as_f64(), o["c"].as_f64()) {
                (Some(a), Some(b), Some(c)) => format!("{method} (a {a:.2}, b {b:.2}, c {c:.2})"),
                _ => method.to_string(),
            }
        }
        _ => method.to_string(),
    }
}
