dpc::model! {
    pub Plant {
        states { x }
        equations {
            der(x) = -k * x;
        }
        params { k = 1.0 }
    }
}

fn main() {}
