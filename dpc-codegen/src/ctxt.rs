//! Error collection for the whole expansion.
//!
//! Every check records its errors here instead of returning at the first one, so the user
//! sees all problems of a model at once, each spanning the offending tokens (the pattern of
//! `serde_derive_internals::Ctxt`).

use quote::ToTokens;
use std::fmt::Display;

/// Collects spanned errors during lowering and checking.
#[derive(Default)]
pub struct Ctxt {
    errors: Vec<syn::Error>,
}

impl Ctxt {
    /// A fresh, empty context.
    pub fn new() -> Self {
        Self::default()
    }

    /// Record an error spanning `tokens`.
    pub fn error_spanned_by<T: ToTokens, M: Display>(&mut self, tokens: T, message: M) {
        self.errors.push(syn::Error::new_spanned(tokens, message));
    }

    /// Record an error at `span`.
    pub fn error_at<M: Display>(&mut self, span: proc_macro2::Span, message: M) {
        self.errors.push(syn::Error::new(span, message));
    }

    /// Record an already built error.
    pub fn push(&mut self, error: syn::Error) {
        self.errors.push(error);
    }

    /// Whether any error was recorded.
    pub fn has_errors(&self) -> bool {
        !self.errors.is_empty()
    }

    /// All recorded errors combined into one, or `Ok(())` if there were none. An error with
    /// the message and position of an earlier one is dropped: a family of equations written
    /// once (`for i in 0..N { ... }`) is checked once per index, and a mistake that does not
    /// depend on the index is reported once, on its tokens.
    pub fn check(self) -> syn::Result<()> {
        let mut seen = std::collections::HashSet::new();
        let mut iter = self
            .errors
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
