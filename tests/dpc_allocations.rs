//! A DPC control update for a fixed-size generated model allocates nothing on the heap
//! after setup: counted with a global allocator wrapper.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use std::sync::Arc;

use dpc::core::dpc::{Dpc, DpcOptions, Extraction};
use dpc::core::linalg::NalgebraLu;
use dpc_models::wheel_design;
use dpc_models::{Wheel, WheelReference, WheelTracking};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// How the controller of a test is set up.
#[derive(Debug, Clone, Copy)]
enum Feedback {
    /// Plain DPC.
    None,
    /// The paper's preliminary feedback about the nominal motion.
    AboutNominal,
    /// The same `K_n` about the reference (shared with the controller through an `Arc`).
    AboutReference,
}

#[test]
fn wheel_control_updates_do_not_allocate() {
    let feedbacks = [
        Feedback::None,
        Feedback::AboutNominal,
        Feedback::AboutReference,
    ];
    for (feedback, extraction) in feedbacks
        .into_iter()
        .flat_map(|f| [(f, Extraction::FirstUsable), (f, Extraction::Extrapolated)])
    {
        let reference = Arc::new(WheelReference::default());
        let mut dpc = Dpc::new(
            WheelTracking::default(),
            reference.clone(),
            NalgebraLu::<{ WheelTracking::N_EQUATIONS }>::new(),
            DpcOptions {
                extraction,
                ..DpcOptions::default()
            },
        )
        .expect("controller");
        let mut law = wheel_design::prefeedback(&Wheel::default()).expect("design");
        match feedback {
            Feedback::None => {}
            Feedback::AboutNominal => dpc = dpc.with_prefeedback(law).expect("prefeedback"),
            Feedback::AboutReference => {
                law.nominal = Box::new(wheel_design::about_reference(reference).expect("map"));
                dpc = dpc.with_prefeedback(law).expect("prefeedback");
            }
        }
        let mut u = [0.0; 2];
        let mut x = [std::f64::consts::FRAC_PI_2, 0.0, 0.0, 0.0, -6.0];
        // The first update warms up; every later one must not allocate.
        dpc.control(0.0, &x, &mut u).expect("first update");
        let before = ALLOCATIONS.load(Ordering::SeqCst);
        for k in 1..50 {
            let t = k as f64 * 0.05;
            x[1] = -6.0 * t;
            x[0] += 0.001;
            dpc.control(t, &x, &mut u).expect("update");
        }
        let after = ALLOCATIONS.load(Ordering::SeqCst);
        assert_eq!(
            after - before,
            0,
            "allocations during 49 control updates ({feedback:?}, {extraction:?})"
        );
        assert!(u.iter().all(|v| v.is_finite()));
    }
}
