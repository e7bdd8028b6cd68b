//! Build script of the facade crate. It does nothing unless the feature `casadi-peer` is on:
//! then it compiles CasADi's generated C for the wheel (written by `bench/casadi/run.sh`, or
//! found in the directory `DPC_CASADI_DIR`) with `-O2` into the benchmark
//! `benches/casadi_peer.rs`. Neither CI nor `cargo test` turns the feature on.

fn main() {
    #[cfg(feature = "casadi-peer")]
    casadi_peer();
}

#[cfg(feature = "casadi-peer")]
fn casadi_peer() {
    use std::path::PathBuf;
    println!("cargo:rerun-if-env-changed=DPC_CASADI_DIR");
    let dir = match std::env::var_os("DPC_CASADI_DIR") {
        Some(d) => PathBuf::from(d),
        None => PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("set by cargo"))
            .join("bench/casadi/generated"),
    };
    let source = dir.join("wheel_casadi.c");
    println!("cargo:rerun-if-changed={}", source.display());
    if !source.is_file() {
        panic!(
            "feature `casadi-peer`: {} does not exist; generate it with `bash bench/casadi/run.sh` \
             (or point DPC_CASADI_DIR at a directory holding wheel_casadi.c)",
            source.display()
        );
    }
    cc::Build::new()
        .file(&source)
        .opt_level(2)
        .warnings(false)
        .compile("wheel_casadi");
}
