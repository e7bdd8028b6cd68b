//! Every malformed model is a compile error on the offending tokens, saying what is wrong and
//! what was expected. Each case in `tests/ui/` has its expected diagnostics in a `.stderr`
//! file beside it (regenerate after a deliberate change with `TRYBUILD=overwrite`).

#[test]
fn malformed_models_are_compile_errors() {
    let t = trybuild::TestCases::new();
    t.compile_fail("tests/ui/*.rs");
}

/// Expressions as deep as plain Rust accepts compile through the macro as well.
#[test]
fn deep_expressions_compile() {
    let t = trybuild::TestCases::new();
    t.pass("tests/ui-pass/*.rs");
}
