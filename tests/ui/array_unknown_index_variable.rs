dpc::model! {
    pub Chain {
        consts { N = 2 }
        states { x[N] }
        equations {
            for i in 0..N {
                der(x[j]) = -x[i];
            }
        }
    }
}

fn main() {}
