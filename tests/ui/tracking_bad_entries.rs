dpc::model! {
    pub Plant {
        states { x, v }
        inputs { u }
        equations {
            der(x) = v;
            der(v) = u;
        }
        outputs { x }
        tracking PlantTracking { x: [-1.0, fast], v: [1.0] }
    }
}

fn main() {}
