//! Rebuilds the crate when its profile-guided-optimisation inputs change (pgo/rustc-wrapper
//! adds the profile to the compiler's command line, which Cargo does not see): a new
//! profile, or a wrapper that applies it differently, then takes effect at the next build.

fn main() {
    for input in [
        "pgo/spectral-render.profdata",
        "pgo/METADATA",
        "pgo/rustc-wrapper",
    ] {
        println!("cargo::rerun-if-changed={input}");
    }
    println!("cargo::rerun-if-env-changed=SPECTRAL_RENDER_PGO");
}
