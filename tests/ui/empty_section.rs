dpc::model! {
    pub Plant {
        params {}
        states { x }
        inputs {}
        equations {
            der(x) = -x;
        }
    }
}

fn main() {}
