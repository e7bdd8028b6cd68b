dpc::model! {
    pub Plant {
        params { Ok = 1.0 }
        states { None, Some }
        inputs { usize }
        equations {
            der(None) = Some;
            der(Some) = Ok * usize;
        }
        outputs { Err = None }
    }
}

fn main() {}
