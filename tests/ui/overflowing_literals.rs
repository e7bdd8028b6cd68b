dpc::model! {
    pub Plant {
        params { k = 1e400 }
        states { x }
        inputs { u }
        equations {
            der(x) = -k * x + 2e999 * u;
        }
        outputs { y = x }
        tracking PlantTracking { y: [1e400] }
    }
}

fn main() {}
