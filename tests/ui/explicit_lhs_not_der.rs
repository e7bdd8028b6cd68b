dpc::model! {
    pub Plant {
        states { x }
        equations {
            x = der(x);
        }
    }
}

fn main() {}
