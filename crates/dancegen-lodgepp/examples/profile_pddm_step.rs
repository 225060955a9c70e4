//! Times the parts of one PDDM training step (forward, FK losses, discriminator, backward) at
//! the shipped small configuration, to see where training time goes.
//!
//!     cargo run --profile test -p dancegen-lodgepp --example profile_pddm_step

use std::time::Instant;

use dancegen_lodgepp::config::PddmTable;
use dancegen_lodgepp::training::pddm_loss;
use dancegen_nn::burn::tensor::{Distribution, Tensor};
use dancegen_nn::device;

fn main() {
    let dev = device::training();
    let mut table: PddmTable = toml::from_str("").unwrap();
    table.genres = vec!["a".into(), "b".into(), "c".into()];
    let b: usize = std::env::var("B")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(16);
    for (label, refine, disc) in [
        ("full", true, true),
        ("no disc", true, false),
        ("no refine, no disc", false, false),
    ] {
        let mut t = table.clone();
        t.pddm.foot_refine = refine;
        t.use_discriminator = disc;
        let model = t.init(&[0.0; 151], &[1.0; 151], &dev);
        let shift = t.shift.schedule();
        for rep in 0..3 {
            let x = Tensor::<3>::random([b, 128, 151], Distribution::Normal(0.0, 1.0), &dev);
            let m = Tensor::<3>::random([b, 128, 35], Distribution::Normal(0.0, 1.0), &dev);
            let t0 = Instant::now();
            let l = pddm_loss(
                &model,
                t.pddm.canonical_heading,
                x,
                m,
                &vec![0; b],
                &shift,
                &t.weights,
                &t.dropout,
                rep,
            );
            let _: f32 = l.total.clone().into_scalar();
            let t1 = Instant::now();
            let _g = l.total.backward();
            let t2 = Instant::now();
            println!(
                "{label}: forward {:.0} ms, backward {:.0} ms",
                (t1 - t0).as_secs_f64() * 1e3,
                (t2 - t1).as_secs_f64() * 1e3
            );
        }
    }
}
