//! Syntax of the `model!` DSL: the outer structure parsed with `syn`, the expressions with
//! the DSL's own parser ([`crate::expr`]).
//!
//! This layer only recognises the shape of a model: sections, declared names and the
//! expressions inside them, all with their spans. It does not resolve names or check
//! counts; [`crate::lower`] does that and reports every problem it finds at once.
//!
//! ```text
//! model      := attr* vis Ident '{' item* '}'
//! item       := section | 'let' Ident binder* '=' expr ';'
//! section    := 'consts' '{' (Ident '=' expr),* '}'
//!             | 'params' '{' (attr* Ident dims unit? '=' expr),* '}'
//!             | ('states' | 'algebraic' | 'inputs') '{' (attr* Ident dims unit?),* '}'
//!             | 'equations' '{' equation* '}'
//!             | 'outputs' '{' (attr* target unit? ('=' expr)?),* '}'
//!             | 'references' '{' (target '=' expr),* '}'
//!             | 'tracking' Ident '{' (target ':' '[' expr,* ']'),* '}'
//! dims       := ('[' expr ']')*                      lengths of an indexed family
//! unit       := ':' StrLit                           e.g. `theta: "rad"`; for every element
//! binder     := '[' Ident 'in' expr ']'              an index ranging over `a..b`
//! target     := Ident ('[' (Ident 'in' expr | expr) ']')*
//! equation   := expr ';' | 'for' Ident 'in' expr '{' equation* '}'
//! ```

use crate::expr::{parse_expr, parse_expr_without_brace, Expr};
use proc_macro2::{Span, TokenStream};
use syn::ext::IdentExt;
use syn::parse::{Parse, ParseStream};
use syn::{braced, bracketed, Attribute, Ident, LitStr, Token, Visibility};

/// The sections a model may contain, in the order they must appear.
pub const SECTION_ORDER: &[&str] = &[
    "consts",
    "params",
    "states",
    "algebraic",
    "inputs",
    "equations",
    "outputs",
    "references",
    "tracking",
];

/// A whole `model!` invocation.
pub struct ModelDef {
    /// Outer attributes, in particular the doc comment.
    pub attrs: Vec<Attribute>,
    /// Visibility of the generated types.
    pub vis: Visibility,
    /// The model's name (and of the generated type).
    pub name: Ident,
    /// Sections and `let` intermediates in source order.
    pub items: Vec<Item>,
    /// Span of the model body's braces, for errors about missing sections.
    pub body_span: Span,
}

/// One item of a model body.
pub enum Item {
    /// A section such as `states { ... }`.
    Section(Section),
    /// `let name = expr;`, an intermediate shared by all equations and outputs.
    Let(Box<LetDef>),
}

/// A `let` intermediate, or with subscripts (`let c[i in 0..N] = cos(q[i]);`) a family of
/// them.
pub struct LetDef {
    /// The `let` keyword (for spans).
    pub let_token: Token![let],
    /// The defined name.
    pub name: Ident,
    /// The subscripts of a family; empty for a scalar.
    pub subscripts: Vec<Subscript>,
    /// Its defining expression.
    pub expr: Expr,
}

/// A named section with its keyword.
pub struct Section {
    /// The section keyword (`params`, `states`, ...), for spans and messages.
    pub keyword: Ident,
    /// Its contents.
    pub body: SectionBody,
    /// Span of the braces, for "empty section" errors.
    pub brace_span: Span,
}

/// The contents of a section, by kind.
pub enum SectionBody {
    /// `consts { N = 3, ... }`: integer constants for lengths, ranges and indices.
    Consts(Vec<ConstDef>),
    /// `params { m = 1.0, ... }`.
    Params(Vec<ParamDef>),
    /// `states { ... }`.
    States(Vec<NameDef>),
    /// `algebraic { ... }`.
    Algebraic(Vec<NameDef>),
    /// `inputs { ... }`.
    Inputs(Vec<NameDef>),
    /// `equations { ...; ... }`.
    Equations(Vec<EquationItem>),
    /// `outputs { y, z = expr }`.
    Outputs(Vec<OutputDef>),
    /// `references { theta = expr_of_t }`.
    References(Vec<ReferenceDef>),
    /// `tracking Name { output: [roots...] }`.
    Tracking(TrackingDef),
}

/// `N = 3` in `consts`.
pub struct ConstDef {
    /// The constant's name.
    pub name: Ident,
    /// Its value: an integer expression of literals and earlier constants.
    pub value: Expr,
}

/// A declared name with its attributes (doc comments).
pub struct NameDef {
    /// Outer attributes; only doc comments are accepted.
    pub attrs: Vec<Attribute>,
    /// The name.
    pub name: Ident,
    /// The lengths of an indexed family (`q[N]`, `a[2][3]`); empty for a scalar.
    pub dims: Vec<Expr>,
    /// The unit written after the name (`theta: "rad"`), for every element of a family.
    pub unit: Option<LitStr>,
}

/// `name = default` in `params`.
pub struct ParamDef {
    /// Outer attributes; only doc comments are accepted.
    pub attrs: Vec<Attribute>,
    /// Parameter name.
    pub name: Ident,
    /// The lengths of an indexed family; empty for a scalar.
    pub dims: Vec<Expr>,
    /// The unit written after the name (`m: "kg" = 1.0`).
    pub unit: Option<LitStr>,
    /// Default value as written (checked to be numeric by the lowering).
    pub default: Expr,
}

/// One subscript of a target or a `let` family: an index variable with its range
/// (`i in 0..N`) or one index (`2`, `N - 1`).
pub enum Subscript {
    /// `i in a..b`.
    Binder {
        /// The index variable.
        var: Ident,
        /// Its range as written.
        range: Expr,
    },
    /// A single index.
    Index(Expr),
}

/// One equation, or a family of them written once over an index range.
pub enum EquationItem {
    /// `der(x) = expr;` or `lhs == rhs;`.
    Equation(Expr),
    /// `for i in a..b { ... }`.
    For(ForDef),
}

/// `for VAR in RANGE { equations }`.
pub struct ForDef {
    /// The `for` keyword (for spans).
    pub for_token: Token![for],
    /// The index variable.
    pub var: Ident,
    /// Its range as written.
    pub range: Expr,
    /// The equations written once for every index.
    pub body: Vec<EquationItem>,
}

/// An output: a bare name (`theta`, the state of that name) or `name = expr`.
pub struct OutputDef {
    /// Outer attributes; only doc comments are accepted.
    pub attrs: Vec<Attribute>,
    /// Output name.
    pub name: Ident,
    /// Subscripts of an output family (`y[i in 0..N] = ...`); empty for a scalar.
    pub subscripts: Vec<Subscript>,
    /// The unit written after the name (`y: "m" = ...`); a bare output without one takes
    /// the unit of its variable.
    pub unit: Option<LitStr>,
    /// Its expression; `None` means the declared variable of the same name.
    pub expr: Option<Expr>,
}

/// A reference trajectory written as an expression of `t`.
pub struct ReferenceDef {
    /// The output it is a reference for.
    pub output: Ident,
    /// Subscripts selecting elements of an output family.
    pub subscripts: Vec<Subscript>,
    /// Its expression in `t` and parameters.
    pub expr: Expr,
}

/// The `tracking` section: the name of the generated tracking type and `W_i` per output.
pub struct TrackingDef {
    /// Name of the generated tracking-DAE type.
    pub type_name: Ident,
    /// Per output, the negated roots of `W_i(s)`.
    pub entries: Vec<TrackingEntry>,
}

/// `output: [a1, a2, ...]`, meaning `W(s) = (s + a1)(s + a2)...`.
pub struct TrackingEntry {
    /// The output's name.
    pub output: Ident,
    /// Subscripts selecting elements of an output family.
    pub subscripts: Vec<Subscript>,
    /// The bracket, for spans of the whole list.
    pub bracket_span: Span,
    /// The negated roots as written.
    pub roots: Vec<Expr>,
}

/// Parse the body of a `model!` invocation.
///
/// `syn` builds its token buffer by recursion over nested groups, so groups nested deeper
/// than a few levels are first set aside ([`crate::expr::parser::with_stash`]); the
/// expression parser reads them back. Nothing here recurses along an expression's depth.
pub fn parse_model(input: TokenStream) -> syn::Result<ModelDef> {
    crate::expr::parser::with_stash(input, syn::parse2)
}

impl Parse for ModelDef {
    fn parse(input: ParseStream) -> syn::Result<Self> {
        let attrs = input.call(Attribute::parse_outer)?;
        let vis: Visibility = input.parse()?;
        let name: Ident = user_ident(input, "a model")
            .map_err(|e| keyword_or(e, "expected the model's name, e.g. `pub Wheel { ... }`"))?;
        let body;
        let brace = braced!(body in input);
        let mut items = Vec::new();
        while !body.is_empty() {
            items.push(body.parse()?);
        }
        if !input.is_empty() {
            return Err(
                input.error("unexpected tokens after the model body; one model per `model!`")
            );
        }
        Ok(ModelDef {
            attrs,
            vis,
            name,
            items,
            body_span: brace.span.join(),
        })
    }
}

impl Parse for Item {
    fn parse(input: ParseStream) -> syn::Result<Self> {
        if input.peek(Token![let]) {
            let let_token: Token![let] = input.parse()?;
            let name: Ident = user_ident(input, "a `let` intermediate")?;
            let subscripts = subscripts(input)?;
            input.parse::<Token![=]>()?;
            let expr = parse_expr(input)?;
            input.parse::<Token![;]>().map_err(|e| {
                syn::Error::new(e.span(), "expected `;` after the `let` intermediate")
            })?;
            return Ok(Item::Let(Box::new(LetDef {
                let_token,
                name,
                subscripts,
                expr,
            })));
        }
        let keyword: Ident = input.call(syn::ext::IdentExt::parse_any).map_err(|e| {
            syn::Error::new(
                e.span(),
                format!(
                    "expected a section ({}) or a `let` intermediate",
                    SECTION_ORDER.join(", ")
                ),
            )
        })?;
        let kw = keyword.to_string();
        let body_span;
        let body = match kw.as_str() {
            "consts" => {
                let content;
                body_span = braced!(content in input).span.join();
                SectionBody::Consts(comma_list(&content, |c| {
                    let name = user_ident(c, "a constant")?;
                    c.parse::<Token![=]>().map_err(|e| {
                        syn::Error::new(
                            e.span(),
                            format!(
                                "expected `= <integer>` after constant `{name}`, e.g. `{name} = 3`"
                            ),
                        )
                    })?;
                    Ok(ConstDef {
                        name,
                        value: parse_expr(c)?,
                    })
                })?)
            }
            "params" => {
                let content;
                body_span = braced!(content in input).span.join();
                SectionBody::Params(comma_list(&content, parse_param)?)
            }
            "states" | "algebraic" | "inputs" => {
                let content;
                body_span = braced!(content in input).span.join();
                let what = match kw.as_str() {
                    "states" => "a state",
                    "algebraic" => "an algebraic unknown",
                    _ => "an input",
                };
                let names = comma_list(&content, |c| parse_name(c, what))?;
                match kw.as_str() {
                    "states" => SectionBody::States(names),
                    "algebraic" => SectionBody::Algebraic(names),
                    _ => SectionBody::Inputs(names),
                }
            }
            "equations" => {
                let content;
                body_span = braced!(content in input).span.join();
                SectionBody::Equations(equation_items(&content)?)
            }
            "outputs" => {
                let content;
                body_span = braced!(content in input).span.join();
                SectionBody::Outputs(comma_list(&content, parse_output)?)
            }
            "references" => {
                let content;
                body_span = braced!(content in input).span.join();
                SectionBody::References(comma_list(&content, |c| {
                    let output: Ident = c.parse()?;
                    let subscripts = subscripts(c)?;
                    c.parse::<Token![=]>()?;
                    Ok(ReferenceDef {
                        output,
                        subscripts,
                        expr: parse_expr(c)?,
                    })
                })?)
            }
            "tracking" => {
                let type_name: Ident = user_ident(input, "a tracking type").map_err(|e| {
                    keyword_or(
                        e,
                        "expected the name of the generated tracking type, e.g. `tracking WheelTracking { theta: [5.0] }`",
                    )
                })?;
                let content;
                body_span = braced!(content in input).span.join();
                let entries = comma_list(&content, |c| {
                    let output: Ident = c.parse()?;
                    let subscripts = subscripts(c)?;
                    c.parse::<Token![:]>()?;
                    let list;
                    let bracket = bracketed!(list in c);
                    let roots = comma_list(&list, parse_expr)?;
                    Ok(TrackingEntry {
                        output,
                        subscripts,
                        bracket_span: bracket.span.join(),
                        roots,
                    })
                })?;
                SectionBody::Tracking(TrackingDef { type_name, entries })
            }
            _ => {
                return Err(syn::Error::new(
                    keyword.span(),
                    format!(
                        "unknown section `{kw}`; expected one of: {}, or `let name = expr;`",
                        SECTION_ORDER.join(", ")
                    ),
                ))
            }
        };
        Ok(Item::Section(Section {
            keyword,
            body,
            brace_span: body_span,
        }))
    }
}

fn comma_list<T>(
    input: ParseStream,
    f: impl Fn(ParseStream) -> syn::Result<T>,
) -> syn::Result<Vec<T>> {
    let mut out = Vec::new();
    while !input.is_empty() {
        out.push(f(input)?);
        if input.is_empty() {
            break;
        }
        input.parse::<Token![,]>()?;
    }
    Ok(out)
}

/// Marker in the message of a keyword error, so callers keep it instead of a generic one.
const KEYWORD_MARK: &str = "is a Rust keyword";

/// An identifier that names `what`; a keyword gets an error saying so on its token.
fn user_ident(input: ParseStream, what: &str) -> syn::Result<Ident> {
    if input.peek(Ident::peek_any) && !input.peek(Ident) {
        let kw = input.call(Ident::parse_any)?;
        let msg = crate::names::refusal(&kw.to_string(), what).unwrap_or_else(|| {
            format!("`{kw}` {KEYWORD_MARK} and cannot name {what}; choose another name")
        });
        return Err(syn::Error::new(kw.span(), msg));
    }
    input.parse()
}

/// `e` if it is a keyword error from [`user_ident`], else an error with `message` at its span.
fn keyword_or(e: syn::Error, message: &str) -> syn::Error {
    if e.to_string().contains(KEYWORD_MARK) {
        e
    } else {
        syn::Error::new(e.span(), message)
    }
}

/// Equations up to the end of `input`: `expr;` or `for i in a..b { ... }`, nested.
fn equation_items(input: ParseStream) -> syn::Result<Vec<EquationItem>> {
    let mut items = Vec::new();
    while !input.is_empty() {
        if input.peek(Token![for]) {
            let for_token: Token![for] = input.parse()?;
            let var: Ident = input.parse().map_err(|e| {
                syn::Error::new(
                    e.span(),
                    "expected an index variable after `for`, e.g. `for i in 0..N { ... }`",
                )
            })?;
            input.parse::<Token![in]>().map_err(|e| {
                syn::Error::new(
                    e.span(),
                    format!("expected `in` after `for {var}`, e.g. `for {var} in 0..N {{ ... }}`"),
                )
            })?;
            let range = parse_expr_without_brace(input)?;
            let content;
            braced!(content in input);
            let body = equation_items(&content)?;
            // A `;` after the loop's braces is accepted, as in Rust.
            if input.peek(Token![;]) {
                input.parse::<Token![;]>()?;
            }
            items.push(EquationItem::For(ForDef {
                for_token,
                var,
                range,
                body,
            }));
            continue;
        }
        items.push(EquationItem::Equation(parse_expr(input)?));
        if input.is_empty() {
            break;
        }
        input
            .parse::<Token![;]>()
            .map_err(|e| syn::Error::new(e.span(), "expected `;` after an equation"))?;
    }
    Ok(items)
}

/// The lengths `[N][3]` after a declared name.
fn dims(input: ParseStream) -> syn::Result<Vec<Expr>> {
    let mut out = Vec::new();
    while input.peek(syn::token::Bracket) {
        let content;
        bracketed!(content in input);
        out.push(parse_expr(&content)?);
    }
    Ok(out)
}

/// The subscripts `[i in 0..N][2]` after a target or a `let` name.
fn subscripts(input: ParseStream) -> syn::Result<Vec<Subscript>> {
    let mut out = Vec::new();
    while input.peek(syn::token::Bracket) {
        let content;
        bracketed!(content in input);
        if content.peek(Ident) && content.peek2(Token![in]) {
            let var: Ident = content.parse()?;
            content.parse::<Token![in]>()?;
            out.push(Subscript::Binder {
                var,
                range: parse_expr(&content)?,
            });
        } else {
            out.push(Subscript::Index(parse_expr(&content)?));
        }
    }
    Ok(out)
}

/// The unit `: "rad"` after a declared name, if there is one: a non-empty string literal of
/// one line without `[` or `]` (it is shown as `theta [rad]`).
fn unit(input: ParseStream, name: &Ident) -> syn::Result<Option<LitStr>> {
    if !input.peek(Token![:]) {
        return Ok(None);
    }
    input.parse::<Token![:]>()?;
    if !input.peek(LitStr) {
        return Err(input.error(format!(
            "expected the unit of `{name}` as a string literal, e.g. `{name}: \"rad\"`"
        )));
    }
    let lit: LitStr = input.parse()?;
    let text = lit.value();
    let problem = if text.trim().is_empty() {
        Some("is empty")
    } else if text.contains(['\n', '\r']) {
        Some("spans more than one line")
    } else if text.contains(['[', ']']) {
        Some("contains `[` or `]`, which delimit units in listings and figures")
    } else if !lit.suffix().is_empty() {
        Some("has a suffix")
    } else {
        None
    };
    match problem {
        Some(p) => Err(syn::Error::new(
            lit.span(),
            format!("the unit of `{name}` {p}; write one such as `{name}: \"rad\"`"),
        )),
        None => Ok(Some(lit)),
    }
}

fn parse_name(input: ParseStream, what: &str) -> syn::Result<NameDef> {
    let attrs = input.call(Attribute::parse_outer)?;
    let name = user_ident(input, what)?;
    let dims = dims(input)?;
    let unit = unit(input, &name)?;
    Ok(NameDef {
        attrs,
        name,
        dims,
        unit,
    })
}

fn parse_param(input: ParseStream) -> syn::Result<ParamDef> {
    let attrs = input.call(Attribute::parse_outer)?;
    let name: Ident = user_ident(input, "a parameter")?;
    let dims = dims(input)?;
    let unit = unit(input, &name)?;
    input.parse::<Token![=]>().map_err(|e| {
        syn::Error::new(
            e.span(),
            format!("expected `= <default>` after parameter `{name}`, e.g. `{name} = 1.0`"),
        )
    })?;
    Ok(ParamDef {
        attrs,
        name,
        dims,
        unit,
        default: parse_expr(input)?,
    })
}

fn parse_output(input: ParseStream) -> syn::Result<OutputDef> {
    let attrs = input.call(Attribute::parse_outer)?;
    let name: Ident = user_ident(input, "an output")?;
    let subscripts = subscripts(input)?;
    let unit = unit(input, &name)?;
    let expr = if input.peek(Token![=]) {
        input.parse::<Token![=]>()?;
        Some(parse_expr(input)?)
    } else {
        None
    };
    Ok(OutputDef {
        attrs,
        name,
        subscripts,
        unit,
        expr,
    })
}
