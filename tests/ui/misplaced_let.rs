dpc::model! {
    pub Plant {
        states { x }
        equations {
            der(x) = -x;
        }
        let k = 2.0;
    }
}

fn main() {}
