dpc::model! {
    pub Plant {
        states { r#match, x }
        inputs { u }
        equations {
            der(r#match) = x;
            der(x) = u;
        }
    }
}

fn main() {}
