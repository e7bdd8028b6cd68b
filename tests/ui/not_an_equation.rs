dpc::model! {
    pub Plant {
        states { x }
        equations {
            der(x) + x;
        }
    }
}

fn main() {}
