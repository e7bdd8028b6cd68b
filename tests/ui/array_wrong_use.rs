dpc::model! {
    pub Chain {
        consts { N = 2 }
        params { M[N][N] = [[1.0, 0.0], [0.0, 1.0]] }
        states { x[N], x_1 }
        equations {
            der(x[0]) = -x;
            der(x[1]) = M[1] * x[0][1];
            der(x_1) = sum(0..N, |N| x[N]);
        }
    }
}

fn main() {}
