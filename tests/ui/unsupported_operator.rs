dpc::model! {
    pub Plant {
        states { x, y }
        equations {
            der(x) = x % 2.0;
            der(y) = if x { 1.0 } else { 0.0 };
        }
    }
}

fn main() {}
