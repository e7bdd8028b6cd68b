dpc::model! {
    pub Plant {
        states { x, y }
        equations {
            der(x) = sin(x, y);
            der(y) = x.atan2();
        }
    }
}

fn main() {}
