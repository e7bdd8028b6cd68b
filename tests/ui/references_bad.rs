dpc::model! {
    pub Plant {
        states { x, v }
        inputs { u, f }
        equations {
            der(x) = v;
            der(v) = u + f;
        }
        outputs { x, v }
        references { x = sin(v), speed = 1.0 }
    }
}

fn main() {}
