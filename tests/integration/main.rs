//! The integration tests, one binary with a module per area so that a test run links
//! once (matklad, "Delete Cargo Integration Tests"). The tests that count the heap need
//! an allocator of their own and a process to themselves: they are `tests/memory/`.

mod common;

mod accel;
mod adversarial;
mod bench_chart;
mod cli;
mod counts;
mod docs;
mod effects;
mod farm;
mod fuzz_findings;
mod gallery;
mod generate;
mod merge;
mod p3f_reader;
mod render;
mod scale;
mod scale_curve;
mod simd;
mod view;
mod watertight;
