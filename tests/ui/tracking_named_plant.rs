dpc::model! {
    pub Plant {
        states { x }
        inputs { u }
        equations {
            der(x) = u;
        }
        outputs { y = x }
        references { y = 1.0 }
        tracking Plant { y: [1.0] }
    }
}

fn main() {}
