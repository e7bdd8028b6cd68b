dpc::model! {
    pub Plant {
        params { n = 2.0 }
        states { x, y }
        equations {
            der(x) = -x.powi(2.5);
            der(y) = -powi(y, n);
        }
    }
}

fn main() {}
