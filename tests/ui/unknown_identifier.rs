dpc::model! {
    pub Plant {
        params { k = 1.0 }
        states { x }
        equations {
            der(x) = -k * y;
        }
    }
}

fn main() {}
