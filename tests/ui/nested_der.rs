dpc::model! {
    pub Plant {
        states { x, v }
        equations {
            der(der(x)) == -x;
            der(v) = x;
        }
    }
}

fn main() {}
