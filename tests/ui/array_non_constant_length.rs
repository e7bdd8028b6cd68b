dpc::model! {
    pub Chain {
        params { n = 3.0 }
        states { x[n] }
        equations {
            for i in 0..3 {
                der(x[i]) = -x[i];
            }
        }
    }
}

fn main() {}
