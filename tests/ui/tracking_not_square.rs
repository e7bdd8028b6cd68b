dpc::model! {
    pub Plant {
        states { x, v }
        inputs { u }
        equations {
            der(x) = v;
            der(v) = u;
        }
        outputs { x, v }
        tracking PlantTracking { x: [1.0] }
    }
}

fn main() {}
