dpc::model! {
    pub Plant {
        states { x }
        let a = 2.0 * b;
        let b = 3.0;
        equations {
            der(x) = -a * x;
        }
    }
}

fn main() {}
