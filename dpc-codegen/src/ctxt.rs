//! Error collection for the whole expansion.
//!
//! Every check records its errors here instead of returning at the first one, so the user
//! sees all problems of a model at once, each spanning the offending tokens (the pattern of
//! `serde_derive_internals::Ctxt`).

use quote::ToTokens;
use std::fmt::Display;

/// Collects spanned errors during lowering and checking. It must be consumed by
/// [`check`](Self::check): a context dropped unchecked would lose its errors silently, so
/// dropping one is a bug of the macro and panics (outside an unwinding panic), as serde's does.
pub struct Ctxt {
    /// `None` once checked.
    errors: Option<Vec<syn::Error>>,
}

impl Default for Ctxt {
    fn default() -> Self {
        Self {
            errors: Some(Vec::new()),
        }
    }
}

impl Drop for Ctxt {
    fn drop(&mut self) {
        if self.errors.is_some() && !std::thread::panicking() {
            panic!("internal error: an error context was dropped without being checked");
        }
    }
}

impl Ctxt {
    /// A fresh, empty context.
    pub fn new() -> Self {
        Self::default()
    }

    fn errors_mut(&mut self) -> &mut Vec<syn::Error> {
        self.errors
            .as_mut()
            .expect("an error context is not used after `check`")
    }

    /// Record an error spanning `tokens`.
    pub fn error_spanned_by<T: ToTokens, M: Display>(&mut self, tokens: T, message: M) {
        self.errors_mut()
            .push(syn::Error::new_spanned(tokens, message));
    }

    /// Record an error at `span`.
    pub fn error_at<M: Display>(&mut self, span: proc_macro2::Span, message: M) {
        self.errors_mut().push(syn::Error::new(span, message));
    }

    /// Record an already built error.
    pub fn push(&mut self, error: syn::Error) {
        self.errors_mut().push(error);
    }

    /// Whether any error was recorded.
    pub fn has_errors(&self) -> bool {
        self.errors.as_ref().is_some_and(|e| !e.is_empty())
    }

    /// All recorded errors combined into one, or `Ok(())` if there were none. An error with
    /// the message and position of an earlier one is dropped: a family of equations written
    /// once (`for i in 0..N { ... }`) is checked once per index, and a mistake that does not
    /// depend on the index is reported once, on its tokens.
    pub fn check(mut self) -> syn::Result<()> {
        let errors = self.errors.take().unwrap_or_default();
        let mut seen = std::collections::HashSet::new();
        let mut iter = errors
            .into_iter()
            .flat_map(|e| e.into_iter())
            .filter(|e| seen.insert((e.to_string(), format!("{:?}", e.span()))));
        match iter.next() {
            None => Ok(()),
            Some(mut first) => {
                for e in iter {
                    first.combine(e);
                }
                Err(first)
            }
        }
    }
}
