//! A DPC control update for a fixed-size generated model allocates nothing on the heap
//! after setup: counted with a global allocator wrapper.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use dpc::core::dpc::{Dpc, DpcOptions, Extraction};
use dpc::core::linalg::NalgebraLu;
use dpc_models::{WheelReference, WheelTracking};

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

#[test]
fn wheel_control_updates_do_not_allocate() {
    for extraction in [Extraction::FirstUsable, Extraction::Extrapolated] {
        let mut dpc = Dpc::new(
            WheelTracking::default(),
            WheelReference::default(),
            NalgebraLu::<7>::new(),
            DpcOptions {
                extraction,
                ..DpcOptions::default()
            },
        )
        .expect("controller");
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
        assert_eq!(after - before, 0, "allocations during 49 control updates");
        assert!(u.iter().all(|v| v.is_finite()));
    }
}
