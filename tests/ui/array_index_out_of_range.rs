dpc::model! {
    pub Chain {
        consts { N = 3 }
        params { k = 1.0 }
        states { x[N] }
        equations {
            for i in 0..N {
                der(x[i]) = -k * (x[i] - x[i + 1]);
            }
        }
    }
}

fn main() {}
