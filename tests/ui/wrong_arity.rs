dpc::model! {
    pub Plant {
        states { x, y }
        equations {
            der(x) = sin(x, y) + max(x);
            der(y) = x.atan2() + min(x, y, 1.0) * x.max(y, x);
        }
    }
}

fn main() {}
