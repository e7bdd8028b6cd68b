dpc::model! {
    pub Plant {
        states { x }
        equations {
            der(x) = -sigmoid(x);
        }
    }
}

fn main() {}
