dpc::model! {
    pub Plant {
        states { x, v }
        equations {
            der(x) = v;
            der(v) == der(x + v);
        }
    }
}

fn main() {}
