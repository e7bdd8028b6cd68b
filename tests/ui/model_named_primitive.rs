dpc::model! {
    pub f64 {
        states { x }
        inputs { u }
        equations {
            der(x) = u;
        }
        outputs { y = x }
    }
}

fn main() {}
