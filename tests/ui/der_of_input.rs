dpc::model! {
    pub Plant {
        states { x }
        inputs { u }
        equations {
            der(x) = der(u);
        }
    }
}

fn main() {}
