//! Compiles the C baselines of benches/baselines/ as their own headers say they are built
//! (`cc -O3 -march=native`), each in its own unit (both define `main`, `now`, their RNG state).

fn main() {
    for file in ["c/capture.c", "c/phase.c", "c/slab.c"] {
        println!("cargo:rerun-if-changed={file}");
    }
    for file in ["phase_ref.c", "slab_ref.c"] {
        println!("cargo:rerun-if-changed=../benches/baselines/{file}");
    }
    cc::Build::new()
        .files(["c/capture.c", "c/phase.c", "c/slab.c"])
        .opt_level(3)
        .flag("-march=native")
        .warnings(false)
        .compile("baselines");
    println!("cargo:rustc-link-lib=m");
}
