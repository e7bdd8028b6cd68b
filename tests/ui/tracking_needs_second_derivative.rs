// Steps through an implicit equation differentiate it (`der2(v)` joins the tracking DAE), but
// not beyond the relative degree: the fourth step would need the derivative of the input.
dpc::model! {
    pub Plant {
        states { x, v, w }
        inputs { u }
        equations {
            der(x) = v;
            (2.0 + x.powi(2)) * der(v) == w;
            der(w) = u;
        }
        outputs { x }
        tracking PlantTracking { x: [1.0, 2.0, 3.0, 4.0] }
    }
}

fn main() {}
