dpc::model! {
    pub Plant {
        params { k = 2.0 }
        states { x, z }
        inputs { u, v }
        equations {
            der(x) = -x;
            der(z) = u + v;
        }
        outputs { y = k, w = -x + 0.0 * u }
        tracking PlantTracking { y: [], w: [1.0] }
    }
}

fn main() {}
