dpc::model! {
    pub Plant {
        states { theta: "rad]", omega }
        equations {
            der(theta) = omega;
            der(omega) = -theta;
        }
    }
}

fn main() {}
