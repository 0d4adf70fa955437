//! A global allocator that counts the heap held now and at its peak, and the calls that
//! asked for memory. `main.rs` runs one test at a time, so what it counts is that test's.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use p3trace::render::{RenderOptions, RenderReport, Stage};
use p3trace::scene::Scene;

/// The system allocator, counting the bytes held now and at most.
pub struct Counting;

static HELD: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
static CALLS: AtomicUsize = AtomicUsize::new(0);

fn grew(bytes: usize) {
    CALLS.fetch_add(1, Ordering::Relaxed);
    let now = HELD.fetch_add(bytes, Ordering::Relaxed) + bytes;
    PEAK.fetch_max(now, Ordering::Relaxed);
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        HELD.fetch_sub(layout.size(), Ordering::Relaxed);
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            // Counted as held at both sizes for the moment of the copy.
            grew(new_size);
            HELD.fetch_sub(layout.size(), Ordering::Relaxed);
        }
        p
    }
}

/// How many times memory was asked for (allocations and reallocations) so far.
pub fn calls() -> usize {
    CALLS.load(Ordering::Relaxed)
}

/// Starts a measurement: the bytes held now, from which [`peak_since`] counts.
pub fn start() -> usize {
    let before = HELD.load(Ordering::Relaxed);
    PEAK.store(before, Ordering::Relaxed);
    before
}

/// The most bytes held since [`start`] returned `before`, above it.
pub fn peak_since(before: usize) -> usize {
    PEAK.load(Ordering::Relaxed) - before
}

/// The bytes held now above `before`.
pub fn held_since(before: usize) -> usize {
    HELD.load(Ordering::Relaxed) - before
}

/// Renders `scene` as its file asks, then prints the heap held once the scene is stored
/// and once its structure is built, and checks the heap at the peak since [`start`]
/// returned `before`, per primitive of the `count` of `kind`: at most `max_bytes` each,
/// and where `max_held` is given, at most that many held once built.
pub fn render_within(
    scene: &Scene,
    before: usize,
    count: usize,
    kind: &str,
    (max_bytes, max_held): (f64, Option<f64>),
) -> RenderReport {
    let stored = held_since(before);
    let options = RenderOptions::from_scene(scene);
    let stage = Stage::new(scene, &options);
    let built = held_since(before);
    let report = stage.render(&scene.camera, &options).unwrap();
    let peak = peak_since(before);
    let (each, held) = (peak as f64 / count as f64, built as f64 / count as f64);
    eprintln!(
        "{}: stored in {:.0} MB ({:.1} bytes each), {:.1} bytes each held once built; \
         peak of the render {:.0} MB, {each:.1} bytes per {kind}; {} in {:.1} s",
        scene.name,
        stored as f64 / 1e6,
        stored as f64 / count as f64,
        held,
        peak as f64 / 1e6,
        report.accel_name,
        (report.build_time + report.elapsed).as_secs_f64()
    );
    assert!(
        each <= max_bytes,
        "{each:.1} bytes per {kind} at the peak, above the stated {max_bytes}"
    );
    if let Some(max_held) = max_held {
        assert!(
            held <= max_held,
            "{held:.1} bytes per {kind} held once built, above the stated {max_held}"
        );
    }
    report
}
