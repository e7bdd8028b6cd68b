dpc::model! {
    pub Plant {
        params { PI = 3.0 }
        states { t, x__y }
        equations {
            der(t) = 1.0;
            der(x__y) = 1.0;
        }
    }
}

fn main() {}
