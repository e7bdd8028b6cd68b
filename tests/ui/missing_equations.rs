dpc::model! {
    pub Plant {
        states { x }
    }
}

fn main() {}
