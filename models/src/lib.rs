//! Plants declared with `dpc::model!`.
