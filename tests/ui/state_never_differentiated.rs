dpc::model! {
    pub Plant {
        states { x, y }
        equations {
            der(x) = -y;
            y == x.powi(2);
        }
    }
}

fn main() {}
