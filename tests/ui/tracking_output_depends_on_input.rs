dpc::model! {
    pub Plant {
        states { x }
        inputs { u }
        equations {
            der(x) = -x + u;
        }
        outputs { y = x + 0.1 * u }
        tracking PlantTracking { y: [1.0] }
    }
}

fn main() {}
