dpc::model! {
    pub Plant {
        states { x }
        algebraic { z }
        equations {
            der(x) = -x;
            0.0 == x - 1.0;
        }
    }
}

fn main() {}
