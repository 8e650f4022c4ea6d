//! `cargo bench`: what the lab spends its time on, on one thread.
//!
//! - one drive step of the settled thesis bed (358 spheres, 40 Hz, Γ 20), with
//!   the scene's friction and without;
//! - one step of a 20 000-sphere lattice bed (`vlab::dem::testbed`);
//! - Yang's method on a 5 s, 40 kHz two-channel record, planning the FFT.
//!
//! Each step bench counts particles, so divan prints particle-steps per
//! second. The thesis bed is poured and settled once, before the benches.

use std::f64::consts::PI;
use std::sync::OnceLock;

use divan::counter::ItemsCount;
use divan::{Bencher, black_box};
use vlab::dem::World;
use vlab::dem::testbed::lattice_bed;
use vlab::experiment::bed::settle::{SettledBed, prepare_drive, settle_bed};
use vlab::scene::Scene;
use vlab::signals::{PowerOptions, yang_power};

fn main() {
    // One thread for rayon: the benches time one core (a world's step runs
    // on the caller alone unless given threads).
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build_global()
        .expect("one thread");
    divan::main();
}

/// The thesis bed, settled once for all benches.
fn thesis_bed() -> &'static SettledBed {
    static BED: OnceLock<SettledBed> = OnceLock::new();
    BED.get_or_init(|| settle_bed(&Scene::thesis(), &mut |_| {}).expect("bed"))
}

/// Times drive steps of the thesis bed under `scene`'s laws.
fn drive_steps(bencher: Bencher, scene: &Scene) {
    let dt = scene.drive_dt_s(&scene.drive(40.0, 20.0).expect("valid drive"));
    let mut world: World = prepare_drive(thesis_bed(), scene, dt).expect("drive");
    let n = world.particles.len();
    let amplitude = 20.0 * 9.81 / (2.0 * PI * 40.0).powi(2);
    let mut k = 0u64;
    bencher.counter(ItemsCount::new(n)).bench_local(|| {
        k += 1;
        let u = amplitude * (2.0 * PI * 40.0 * k as f64 * dt).sin();
        world.step(u).expect("step");
    });
}

#[divan::bench(sample_count = 50, sample_size = 200)]
fn thesis_step(bencher: Bencher) {
    drive_steps(bencher, &Scene::thesis());
}

#[divan::bench(sample_count = 50, sample_size = 200)]
fn thesis_step_frictionless(bencher: Bencher) {
    let mut scene = Scene::thesis();
    scene.contact.particle_particle.friction = 0.0;
    scene.contact.particle_wall.friction = 0.0;
    drive_steps(bencher, &scene);
}

#[divan::bench(sample_count = 20, sample_size = 5)]
fn lattice_bed_20000_step(bencher: Bencher) {
    let mut world = lattice_bed(20_000, 0.52, 1).expect("bed");
    for _ in 0..20 {
        world.step(0.0).expect("step");
    }
    bencher
        .counter(ItemsCount::new(world.particles.len()))
        .bench_local(|| world.step(0.0).expect("step"));
}

#[divan::bench(sample_count = 20)]
fn yang_power_5s_record(bencher: Bencher) {
    let (rate, f0) = (40_000.0, 40.0);
    let w = 2.0 * PI * f0;
    let (force, accel): (Vec<f64>, Vec<f64>) = (0..200_000)
        .map(|i| {
            let t = f64::from(i) / rate;
            let a = 196.0 * (w * t).cos() + 20.0 * (3.0 * w * t + 0.4).cos();
            (0.3 * a + 2.0 * (w * t + 1.2).cos(), a)
        })
        .unzip();
    let opts = PowerOptions::default();
    bencher.bench_local(|| {
        yang_power(black_box(&force), black_box(&accel), rate, f0, &opts).expect("power")
    });
}
