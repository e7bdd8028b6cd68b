//! Which user names the expansion can carry, and why the others are refused.
//!
//! The generated code binds the names of parameters, states, algebraic unknowns and inputs as
//! plain `f64` locals (`let x: f64 = __x[0];`) in the routines it emits, declares the items
//! `<Model>`, `<Model>Params`, the tracking type and `<Model>Reference` in the caller's
//! module, and refers to the primitive types `f64`, `usize`, `str` and `bool` unqualified.
//! A name is refused here, on its own tokens, when it would break that code instead of
//! naming a variable:
//!
//! * a Rust keyword (strict, reserved or edition-dependent such as `gen`): it cannot be a
//!   binding or a type name;
//! * a unit or tuple variant of the prelude (`None`, `Some`, `Ok`, `Err`): as a `let`
//!   pattern it matches the variant instead of binding a local;
//! * a primitive type name (`f64`, `usize`, ...): as a generated type it would shadow the
//!   primitive the generated signatures use; as a variable it is refused too, for one rule;
//! * `t` (time) and names containing `__` (generated locals), checked in [`crate::lower`].
//!
//! Names of items or constants the caller defines in the same module cannot be seen by a
//! macro; a unit struct or `const` of the same name as a state shadows the binding there
//! (as it would in handwritten code).

use syn::ext::IdentExt;
use syn::Ident;

/// Strict and reserved keywords of all editions, and the contextual ones that cannot be
/// bindings (`gen` is reserved from Rust 2024).
pub const KEYWORDS: &[&str] = &[
    "as", "async", "await", "break", "const", "continue", "crate", "dyn", "else", "enum", "extern",
    "false", "fn", "for", "if", "impl", "in", "let", "loop", "match", "mod", "move", "mut", "pub",
    "ref", "return", "self", "Self", "static", "struct", "super", "trait", "true", "type",
    "unsafe", "use", "where", "while", "abstract", "become", "box", "do", "final", "gen", "macro",
    "override", "priv", "try", "typeof", "unsized", "virtual", "yield", "union",
];

/// Unit and tuple variants in the prelude: a `let` with one of these names is a pattern.
pub const PRELUDE_VARIANTS: &[&str] = &["None", "Some", "Ok", "Err"];

/// The primitive types of Rust.
pub const PRIMITIVE_TYPES: &[&str] = &[
    "bool", "char", "str", "f16", "f32", "f64", "f128", "i8", "i16", "i32", "i64", "i128", "isize",
    "u8", "u16", "u32", "u64", "u128", "usize",
];

/// Why `text` (a name as written, without `r#`) cannot name `what`, if it cannot.
pub fn refusal(text: &str, what: &str) -> Option<String> {
    if KEYWORDS.contains(&text) {
        return Some(format!(
            "`{text}` is a Rust keyword and cannot name {what}; choose another name"
        ));
    }
    if PRELUDE_VARIANTS.contains(&text) {
        return Some(format!(
            "`{text}` is a variant of the Rust prelude (`Option`/`Result`) and cannot name {what}: the generated code binds names as `let` locals, and `let {text}` would match the variant instead of binding a variable; choose another name"
        ));
    }
    if PRIMITIVE_TYPES.contains(&text) {
        return Some(format!(
            "`{text}` is a primitive type of Rust and cannot name {what}: the generated code uses `{text}` as a type; choose another name"
        ));
    }
    None
}

/// [`refusal`] for a parsed identifier (raw identifiers are judged by their name).
pub fn check(ident: &Ident, what: &str) -> Option<String> {
    refusal(&ident.unraw().to_string(), what)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_the_whole_class() {
        for name in [
            "fn", "Self", "gen", "None", "Some", "Ok", "Err", "f64", "usize", "str",
        ] {
            assert!(refusal(name, "a state").is_some(), "{name}");
        }
        for name in ["x", "theta", "Option", "Vec", "sin", "c", "params"] {
            assert!(refusal(name, "a state").is_none(), "{name}");
        }
        let raw: Ident = syn::parse_str("r#None").expect("raw identifier");
        assert!(check(&raw, "a state").is_some());
    }
}
