dpc::model! {
    pub Plant {
        states { x, v }
        equations {
            der(x) = v;
            der(v) = -x;
            der(x) == v;
        }
    }
}

fn main() {}
