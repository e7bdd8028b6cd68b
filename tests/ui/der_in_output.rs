dpc::model! {
    pub Plant {
        states { x }
        let rate = der(x);
        equations {
            der(x) = -x;
        }
        outputs { y = der(x), r = rate, missing }
    }
}

fn main() {}
