//! Plant files read at run time.
//!
//! A plant file (by convention `NAME.dpc`) holds exactly what goes inside
//! `dpc::model! { ... }`: the same grammar, parsed by the same parser and checked by the same
//! checks as the macro ([`dpc_codegen`]), differentiated by the same symbolic engine and the
//! same derive pass. Where the macro then emits Rust, this crate compiles every routine's
//! roots into a [`tape`] (a flat instruction list over the CSE-scheduled graph), so a plant
//! needs no Rust toolchain at run time:
//!
//! * [`RuntimePlant`] implements [`dpc_core::DaeModel`] (residual, Jacobian blocks with their
//!   structural sparsity, iteration matrix, outputs and output Jacobians) and, for a plant
//!   with position-constraint rows, their exact derivatives as the macro emits them
//!   (`constraint_gradient`, `constraint_time_derivative`, `constraint_curvature`, from tapes
//!   of the derive pass's second derivatives), so the closed loop's index reduction differences
//!   nothing for a plant file either;
//! * [`RuntimeTracking`] implements [`dpc_core::TrackingDae`] for the `tracking` section
//!   (the Hirschorn rows, `W` changeable at run time, relative degrees);
//! * [`RuntimeReference`] implements [`dpc_core::Reference`] for the `references` section,
//!   with exact derivatives.
//!
//! All three are `Clone + Send + Sync`; the parameters are a run-time vector with names
//! ([`RuntimeParams`]), shared by the plant and its tracking DAE as for generated types.
//!
//! ```
//! use dpc_core::DaeModel;
//!
//! let model = dpc_runtime::parse(
//!     "cart.dpc",
//!     "Cart {
//!         params { m = 2.0 }
//!         states { x, v }
//!         inputs { f }
//!         equations { der(x) = v; m * der(v) == f; }
//!         outputs { x }
//!         tracking CartTracking { x: [1.0, 2.0] }
//!     }",
//! )?;
//! let plant = model.plant();
//! let mut r = [0.0; 2];
//! plant.residual(0.0, &[1.0, 0.5], &[0.5, 1.0], &[], &[2.0], &mut r);
//! assert_eq!(r, [0.0, 0.0]);
//! assert_eq!(model.relative_degrees(), &[Some(2)]);
//!
//! // A bad file gives the macro's messages, one FILE:LINE:COLUMN line each.
//! let err = dpc_runtime::parse("bad.dpc", "Bad {\n  states { x }\n  equations { der(x) = y; }\n}")
//!     .unwrap_err();
//! assert!(err.to_string().starts_with("bad.dpc:3:24: unknown identifier `y`"), "{err}");
//! # Ok::<(), dpc_runtime::PlantFileError>(())
//! ```
#![warn(missing_docs)]

mod model;
pub mod tape;

pub use dpc_codegen::hirschorn::RelativeDegree;
pub use model::{RuntimeModel, RuntimeParams, RuntimePlant, RuntimeReference, RuntimeTracking};

use std::path::Path;
use std::str::FromStr;

use thiserror::Error;

/// One error of a plant file, at a position in it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Diagnostic {
    /// Line, from 1.
    pub line: usize,
    /// Column, from 1 (in characters).
    pub column: usize,
    /// The message, as the macro gives it.
    pub message: String,
}

/// Why a plant file cannot be used.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum PlantFileError {
    /// The file could not be read.
    #[error("{path}: cannot read: {message}")]
    Read {
        /// The file.
        path: String,
        /// What kind of failure the system reported.
        kind: std::io::ErrorKind,
        /// The system's reason.
        message: String,
    },
    /// The file is not UTF-8 text.
    #[error(
        "{path}:{line}:{column}: the file is not UTF-8 text (invalid byte at offset {offset})"
    )]
    NotUtf8 {
        /// The file.
        path: String,
        /// Line of the first invalid byte.
        line: usize,
        /// Column of the first invalid byte.
        column: usize,
        /// Byte offset of the first invalid byte.
        offset: usize,
    },
    /// The text is not a valid model: every error found, in order, one line each.
    #[error("{}", lines(.path, .diagnostics))]
    Invalid {
        /// The file.
        path: String,
        /// The errors, each at its position.
        diagnostics: Vec<Diagnostic>,
    },
    /// A routine reads a symbol its layout has no place for: an inconsistency between the
    /// compiler's passes, reported instead of evaluating something else.
    #[error("{path}: internal error: `{symbol}` has no place in the routines of `{model}`")]
    Unplaced {
        /// The file.
        path: String,
        /// The generated type.
        model: String,
        /// The symbol.
        symbol: String,
    },
}

fn lines(path: &str, diagnostics: &[Diagnostic]) -> String {
    diagnostics
        .iter()
        .map(|d| format!("{path}:{}:{}: {}", d.line, d.column, d.message))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Line and column (both from 1) of byte `offset` of `text`.
fn position(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[start..].chars().count() + 1)
}

/// Read and compile the plant file at `path`.
///
/// # Errors
/// [`PlantFileError::Read`] for a missing or unreadable file, [`PlantFileError::NotUtf8`],
/// and the errors of [`parse`].
pub fn load(path: impl AsRef<Path>) -> Result<RuntimeModel, PlantFileError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| PlantFileError::Read {
        path: name.clone(),
        kind: e.kind(),
        message: e.to_string(),
    })?;
    let text = String::from_utf8(bytes).map_err(|e| {
        let offset = e.utf8_error().valid_up_to();
        let valid = String::from_utf8_lossy(&e.as_bytes()[..offset]).into_owned();
        let (line, column) = position(&valid, offset);
        PlantFileError::NotUtf8 {
            path: name.clone(),
            line,
            column,
            offset,
        }
    })?;
    parse(&name, &text)
}

/// Compile the text of a plant file; `origin` names it in errors.
///
/// # Errors
/// [`PlantFileError::Invalid`] with every error the macro would report for the same text,
/// each at its line and column.
pub fn parse(origin: &str, text: &str) -> Result<RuntimeModel, PlantFileError> {
    let tokens = proc_macro2::TokenStream::from_str(text).map_err(|e| {
        let start = e.span().start();
        PlantFileError::Invalid {
            path: origin.to_string(),
            diagnostics: vec![Diagnostic {
                line: start.line.max(1),
                column: start.column + 1,
                message: format!("cannot read the text as tokens: {e}"),
            }],
        }
    })?;
    let (lowered, derived) = dpc_codegen::derive_model(tokens).map_err(|e| invalid(origin, e))?;
    RuntimeModel::compile(origin, lowered, derived)
}

/// The errors of `syn` as diagnostics. An error about the whole input (an empty file) is at
/// its start.
fn invalid(origin: &str, err: syn::Error) -> PlantFileError {
    let diagnostics = err
        .into_iter()
        .map(|e| {
            let start = e.span().start();
            Diagnostic {
                line: start.line.max(1),
                column: start.column + 1,
                message: e.to_string(),
            }
        })
        .collect();
    PlantFileError::Invalid {
        path: origin.to_string(),
        diagnostics,
    }
}
