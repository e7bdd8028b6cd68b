dpc::model! {
    pub Plant {
        states { x }
        states { y }
        equations {
            der(x) = -x;
            der(y) = x;
        }
    }
}

fn main() {}
