dpc::model! {
    pub Plant {
        params { k = 1.0, k = 2.0 }
        states { x }
        equations {
            der(x) = -k * y + foo(x) + x.powi(0.5);
        }
    }
}

fn main() {}
