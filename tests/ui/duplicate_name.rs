dpc::model! {
    pub Plant {
        params { k = 1.0 }
        states { x, k }
        equations {
            der(x) = -x;
            der(k) = x;
        }
    }
}

fn main() {}
