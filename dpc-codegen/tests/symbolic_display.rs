//! `display` prints minimal parentheses; this checks they are still *enough*: the text of
//! random expressions is parsed back by an independent recursive-descent parser (usual
//! mathematical precedence, `^` binding tighter than unary minus) and evaluated, and must
//! agree with `Graph::eval` up to rounding (reassociated sums and products round
//! differently).

use dpc_codegen::symbolic::{Func, Graph, Var};
use proptest::prelude::*;

mod symbolic_common;

use symbolic_common as trees;

struct Parser<'a> {
    s: &'a [u8],
    i: usize,
    x: &'a [f64],
}

impl Parser<'_> {
    fn peek(&mut self) -> Option<u8> {
        while self.s.get(self.i) == Some(&b' ') {
            self.i += 1;
        }
        self.s.get(self.i).copied()
    }
    fn eat(&mut self, c: u8) -> bool {
        let hit = self.peek() == Some(c);
        self.i += usize::from(hit);
        hit
    }
    fn sum(&mut self) -> f64 {
        let mut v = self.prod();
        loop {
            if self.eat(b'+') {
                v += self.prod();
            } else if self.eat(b'-') {
                v -= self.prod();
            } else {
                return v;
            }
        }
    }
    fn prod(&mut self) -> f64 {
        let mut v = self.unary();
        loop {
            if self.eat(b'*') {
                v *= self.unary();
            } else if self.eat(b'/') {
                v /= self.unary();
            } else {
                return v;
            }
        }
    }
    fn unary(&mut self) -> f64 {
        if self.eat(b'-') {
            -self.unary()
        } else {
            self.pow()
        }
    }
    fn pow(&mut self) -> f64 {
        let base = self.atom();
        if !self.eat(b'^') {
            return base;
        }
        let neg = self.eat(b'-');
        let e = self.atom();
        let e = if neg { -e } else { e };
        if e.fract() == 0.0 {
            base.powi(e as i32)
        } else {
            base.powf(e)
        }
    }
    fn word(&mut self) -> &str {
        self.peek();
        let start = self.i;
        while self
            .s
            .get(self.i)
            .is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'.' || *c == b'_')
        {
            self.i += 1;
        }
        std::str::from_utf8(&self.s[start..self.i]).unwrap()
    }
    fn atom(&mut self) -> f64 {
        if self.eat(b'(') {
            let v = self.sum();
            assert!(self.eat(b')'), "expected )");
            return v;
        }
        let w = self.word().to_string();
        if let Ok(v) = w.parse::<f64>() {
            return v;
        }
        if let Some(k) = w.strip_prefix('x').and_then(|k| k.parse::<usize>().ok()) {
            return self.x[k];
        }
        assert!(self.eat(b'('), "call expected after {w}");
        let a = self.sum();
        let v = if self.eat(b',') {
            let b = self.sum();
            match w.as_str() {
                "atan2" => a.atan2(b),
                "hypot" => a.hypot(b),
                "max" => a.max(b),
                "min" => a.min(b),
                _ => panic!("unknown binary function {w}"),
            }
        } else {
            Func::from_name(&w)
                .unwrap_or_else(|| panic!("unknown function {w}"))
                .apply(a)
        };
        assert!(self.eat(b')'), "expected ) after call");
        v
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, ..ProptestConfig::default() })]

    #[test]
    fn display_parses_back_to_the_same_value(t in trees::tree(), x in trees::point()) {
        let mut g = Graph::new();
        let e = trees::build(&mut g, &t);
        let d = g.diff(e, Var(0));
        for r in [e, d] {
            let text = g.display(r, &|v| format!("x{}", v.0));
            let mut p = Parser { s: text.as_bytes(), i: 0, x: &x };
            let got = p.sum();
            prop_assert!(p.peek().is_none(), "trailing text in {text}");
            let want = g.eval(r, &|v| x[v.0 as usize]);
            if want.is_finite() && want.abs() < 1e8 && got.is_finite() {
                prop_assert!((got - want).abs() <= 1e-9 * want.abs().max(1.0),
                    "{text}: parsed {got}, eval {want}");
            }
        }
    }
}
