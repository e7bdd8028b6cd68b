dpc::model! {
    pub Plant {
        states { x }
        inputs { u }
        equations {
            der(x) = u;
        }
        outputs { x }
        tracking PlantTracking { x: [1.0, 2.0] }
    }
}

fn main() {}
