dpc::model! {
    pub Plant {
        states { x1, x2, x3 }
        inputs { u }
        equations {
            der(x1) = x2;
            der(x2) = x3;
            der(x3) = u;
        }
        outputs { y = x1 }
        tracking PlantTracking { y: [1e200, 1e200] }
    }
}

fn main() {}
