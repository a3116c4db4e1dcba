//! The WGSL port through Naga (the translator wgpu, Firefox and Deno use) into the languages
//! other renderers take, each checked by the validator the registries offer: SPIR-V by
//! `spirv-val` (Debian's spirv-tools), GLSL ES 3.10 and GLSL 4.50 compute shaders by
//! `glslangValidator` (glslang-tools), and HLSL (shader model 6.0) and MSL written without error
//! (no HLSL or MSL validator is packaged for Linux). Three modules: the phase models and the
//! tabulated one with the test kernel of tests/lavapipe.rs as entry point, the transport
//! tables (T, c, σ and order 1 from a `.ntt` in a storage buffer) with that of
//! tests/tables.rs, and the collector search on the sphere of tests/search.rs.

use std::path::Path;
use std::process::Command;

/// The modules by name: the phase models, the transport tables, the collector search.
fn modules() -> Vec<(&'static str, naga::Module, naga::valid::ModuleInfo)> {
    let phase = format!(
        "{}\n{}\n{}",
        nephele_wgsl::PHASE,
        nephele_wgsl::tabulated(0, 3),
        include_str!("kernel.wgsl")
    );
    let tables = format!(
        "{}\n{}\n{}",
        nephele_wgsl::PHASE,
        nephele_wgsl::tables(0, 3),
        include_str!("tables_kernel.wgsl")
    );
    let search = format!(
        "{}\n{}\n{}\n{}",
        nephele_wgsl::PHASE,
        nephele_wgsl::tables(0, 3),
        nephele_wgsl::SEARCH,
        include_str!("search_kernel.wgsl")
    );
    [("phase", phase), ("tables", tables), ("search", search)]
        .into_iter()
        .map(|(name, source)| {
            let module = naga::front::wgsl::parse_str(&source)
                .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&source)));
            let info = naga::valid::Validator::new(
                naga::valid::ValidationFlags::all(),
                naga::valid::Capabilities::empty(),
            )
            .validate(&module)
            .expect("Naga validates the port with no extra capability");
            (name, module, info)
        })
        .collect()
}

/// What `nephele export-gpu` writes, `tables_module`, is a whole module on its own: Naga parses
/// and validates it with nothing before or after it.
#[test]
fn the_exported_tables_module_stands_alone() {
    let source = nephele_wgsl::tables_module(1, 2);
    let module = naga::front::wgsl::parse_str(&source)
        .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&source)));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::empty(),
    )
    .validate(&module)
    .expect("the exported module validates");
    assert!(source.contains("@group(1) @binding(2)") && source.contains("@group(1) @binding(3)"));
}

/// Runs `tool args…` and asserts it accepts the file.
fn validates(tool: &str, args: &[&str], file: &Path) {
    let out = Command::new(tool)
        .args(args)
        .arg(file)
        .output()
        .unwrap_or_else(|e| {
            panic!("{tool} not found ({e}): apt-get install glslang-tools spirv-tools")
        });
    assert!(
        out.status.success(),
        "{tool} refuses {}:\n{}{}",
        file.display(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn spirv_passes_spirv_val() {
    let dir = std::env::temp_dir().join(format!("nephele-wgsl-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, module, info) in modules() {
        let words = naga::back::spv::write_vec(&module, &info, &Default::default(), None)
            .expect("SPIR-V from Naga");
        let file = dir.join(format!("{name}.spv"));
        std::fs::write(&file, bytemuck::cast_slice::<u32, u8>(&words)).unwrap();
        validates("spirv-val", &["--target-env", "vulkan1.1"], &file);
        println!("SPIR-V {name}: {} words, spirv-val accepts", words.len());
    }
}

#[test]
fn glsl_passes_glslang() {
    let dir = std::env::temp_dir().join(format!("nephele-wgsl-glsl-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for ((module_name, module, info), (name, version)) in modules().iter().flat_map(|m| {
        [
            ("es310", naga::back::glsl::Version::new_gles(310)),
            ("450", naga::back::glsl::Version::Desktop(450)),
        ]
        .map(|v| (m, v))
    }) {
        let mut text = String::new();
        let options = naga::back::glsl::Options {
            version,
            ..Default::default()
        };
        let pipeline = naga::back::glsl::PipelineOptions {
            shader_stage: naga::ShaderStage::Compute,
            entry_point: "main".into(),
            multiview: None,
        };
        naga::back::glsl::Writer::new(
            &mut text,
            module,
            info,
            &options,
            &pipeline,
            naga::proc::BoundsCheckPolicies::default(),
        )
        .and_then(|mut w| w.write())
        .unwrap_or_else(|e| panic!("GLSL {name} of {module_name} from Naga: {e}"));
        let file = dir.join(format!("{module_name}-{name}.comp"));
        std::fs::write(&file, &text).unwrap();
        validates("glslangValidator", &[], &file);
        println!(
            "GLSL {name} {module_name}: {} lines, glslangValidator accepts",
            text.lines().count()
        );
    }
}

#[test]
fn hlsl_and_msl_are_written() {
    for (name, module, info) in modules() {
        let mut hlsl = String::new();
        let options = naga::back::hlsl::Options {
            shader_model: naga::back::hlsl::ShaderModel::V6_0,
            ..Default::default()
        };
        let pipeline = naga::back::hlsl::PipelineOptions {
            entry_point: Some((naga::ShaderStage::Compute, "main".into())),
        };
        naga::back::hlsl::Writer::new(&mut hlsl, &options, &pipeline)
            .write(&module, &info, None)
            .expect("HLSL from Naga");
        assert!(hlsl.contains("[numthreads(64, 1, 1)]"));
        let (msl, _) =
            naga::back::msl::write_string(&module, &info, &Default::default(), &Default::default())
                .expect("MSL from Naga");
        assert!(msl.contains("kernel void"));
        println!(
            "{name}: HLSL {} lines; MSL {} lines",
            hlsl.lines().count(),
            msl.lines().count()
        );
    }
}
