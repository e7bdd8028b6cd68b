dpc::model! {
    pub Plant {
        states { x }
        constants { k = 1.0 }
        equations {
            der(x) = -x;
        }
    }
}

fn main() {}
