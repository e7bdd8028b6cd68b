dpc::model! {
    pub Plant {
        states { x }
        algebraic { z }
        equations {
            der(x) = z;
            der(z) == x;
        }
    }
}

fn main() {}
