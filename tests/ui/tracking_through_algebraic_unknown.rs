// Within the relative degree (3), but the implicit equation holds an algebraic unknown, whose
// derivative the steps do not take.
dpc::model! {
    pub WithAlgebraic {
        states { x, v, w }
        algebraic { z }
        inputs { u }
        equations {
            der(x) = v;
            (2.0 + x.powi(2)) * der(v) == z;
            0.0 == z - sin(x) * w;
            der(w) = u;
        }
        outputs { x }
        tracking WithAlgebraicTracking { x: [1.0, 2.0, 3.0] }
    }
}

fn main() {}
