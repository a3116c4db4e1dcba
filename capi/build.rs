//! The shared library's SONAME, libnephele_c.so.<ABI version> (capi/src/lib.rs,
//! NEPHELE_ABI_VERSION; capi/tests/abi.rs checks that the two agree), so that a program
//! linked against one ABI never loads another.

const ABI_VERSION: u32 = 2;

fn main() {
    let os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    if os == "linux" || os == "freebsd" {
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,libnephele_c.so.{ABI_VERSION}");
    }
    println!("cargo:rerun-if-changed=build.rs");
}
