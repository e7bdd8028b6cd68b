dpc::model! {
    pub Chain {
        consts { N = 3 }
        params { k[N] = [1.0, 2.0] }
        states { x[N] }
        equations {
            for i in 0..N {
                der(x[i]) = -k[i] * x[i];
            }
        }
    }
}

fn main() {}
