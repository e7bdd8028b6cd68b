dpc::model! {
    pub Plant {
        params { k = "one", c = k }
        states { x }
        equations {
            der(x) = -k * c * x;
        }
    }
}

fn main() {}
