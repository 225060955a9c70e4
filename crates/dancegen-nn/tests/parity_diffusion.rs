//! Diffusion against PyTorch (`tools/parity/diffusion.py`): schedule tables, `q_sample`, EDGE's
//! strided DDIM timesteps, one DDIM step with classifier-free guidance (EDGE scale and
//! ReactDance per-channel scales), one DDPM step, Lodge++'s PDDM forward process and reverse
//! step, and EDGE's long-form overwrite + stitching — within 1e-4 of the largest reference
//! magnitude.

mod common;

use common::{Fixture, assert_close};
use dancegen_motion::rotation::Mat3;
use dancegen_nn::burn::tensor::{Device, Tensor, TensorData};
use dancegen_nn::diffusion::longform::{ChannelLayout, stitch};
use dancegen_nn::diffusion::pddm::ResidualShiftConfig;
use dancegen_nn::diffusion::sampler::combine;
use dancegen_nn::diffusion::{
    BetaSchedule, ChannelScale, Schedule, ddim_step, ddim_timesteps, ddpm_step,
    overwrite_first_halves,
};
use dancegen_nn::{device, loss};

const REL: f64 = 1e-4;

fn vec1(v: Vec<f64>, dev: &Device) -> Tensor<1> {
    let n = v.len();
    let f: Vec<f32> = v.into_iter().map(|x| x as f32).collect();
    Tensor::from_data(TensorData::new(f, [n]), dev)
}

fn ints(fx: &Fixture, key: &str) -> Vec<i64> {
    fx.raw(key).1.iter().map(|&v| v as i64).collect()
}

#[test]
fn schedule_tables_q_sample_and_ddim_timesteps() {
    let fx = Fixture::load("diffusion_schedule");
    let dev = device::inference();
    let probe: Vec<usize> = fx.config["probe_t"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect();
    let t_total = fx.cfg_usize("timesteps");
    for (name, kind) in [
        ("cosine", BetaSchedule::Cosine),
        ("linear", BetaSchedule::Linear),
    ] {
        let s = Schedule::new(kind, t_total);
        let tables: [(&str, &Vec<f64>); 11] = [
            ("betas", &s.betas),
            ("alphas_cumprod", &s.alphas_cumprod),
            ("alphas_cumprod_prev", &s.alphas_cumprod_prev),
            ("sqrt_alphas_cumprod", &s.sqrt_alphas_cumprod),
            (
                "sqrt_one_minus_alphas_cumprod",
                &s.sqrt_one_minus_alphas_cumprod,
            ),
            ("sqrt_recip_alphas_cumprod", &s.sqrt_recip_alphas_cumprod),
            (
                "sqrt_recipm1_alphas_cumprod",
                &s.sqrt_recipm1_alphas_cumprod,
            ),
            ("posterior_variance", &s.posterior_variance),
            (
                "posterior_log_variance_clipped",
                &s.posterior_log_variance_clipped,
            ),
            ("posterior_mean_coef1", &s.posterior_mean_coef1),
            ("posterior_mean_coef2", &s.posterior_mean_coef2),
        ];
        for (key, table) in tables {
            let got = vec1(probe.iter().map(|&t| table[t]).collect(), &dev);
            assert_close(&fx, &format!("out.{name}.{key}"), got, REL);
        }
    }
    let s = Schedule::edge();
    let t: Vec<usize> = ints(&fx, "in.t").iter().map(|&t| t as usize).collect();
    let q = s.q_sample(fx.tensor("in.x0", &dev), &t, fx.tensor("in.noise", &dev));
    assert_close(&fx, "out.q_sample", q, REL);
    for steps in [50usize, 7] {
        let pairs = ddim_timesteps(t_total, steps);
        let mut times: Vec<i64> = pairs.iter().map(|p| p.0 as i64).collect();
        times.push(pairs.last().unwrap().1);
        assert_eq!(
            times,
            ints(&fx, &format!("out.ddim_times_{steps}")),
            "{steps} steps"
        );
    }
}

#[test]
fn ddim_step_with_classifier_free_guidance() {
    let fx = Fixture::load("diffusion_ddim_cfg");
    let dev = device::inference();
    let s = Schedule::edge();
    let (t, tn) = (fx.cfg_usize("t"), fx.config["t_next"].as_i64().unwrap());
    let x_t: Tensor<3> = fx.tensor("in.x_t", &dev);
    let cond: Tensor<3> = fx.tensor("in.x0_cond", &dev);
    let unc: Tensor<3> = fx.tensor("in.x0_uncond", &dev);
    let noise: Tensor<3> = fx.tensor("in.noise", &dev);
    let c = x_t.dims()[2];
    let w = fx.cfg_f64("w");
    let step = |x0: Tensor<3>| {
        ddim_step(
            &s,
            x_t.clone(),
            x0.clamp(-1.0, 1.0),
            t,
            tn,
            fx.cfg_f64("eta"),
            noise.clone(),
        )
    };
    let guided = combine(cond.clone(), unc.clone(), &vec![w; c]);
    assert_close(&fx, "out.next", step(guided.clone()), REL);
    // The step into t = −1 outputs the clamped x̂0 (EDGE's last DDIM step).
    let last = ddim_step(
        &s,
        x_t.clone(),
        guided.clamp(-1.0, 1.0),
        t,
        -1,
        1.0,
        noise.clone(),
    );
    assert_close(&fx, "out.last", last, REL);
    // ReactDance LDCFG: the per-channel weights the sampler builds from the groups.
    let groups: Vec<ChannelScale> = fx.config["groups"]
        .as_array()
        .unwrap()
        .iter()
        .map(|g| ChannelScale {
            range: g[0].as_u64().unwrap() as usize..g[1].as_u64().unwrap() as usize,
            s: g[2].as_f64().unwrap(),
        })
        .collect();
    let mut wc = vec![1.0 + fx.cfg_f64("default_s"); c];
    for g in &groups {
        for ch in g.range.clone() {
            wc[ch] = 1.0 + g.s;
        }
    }
    assert_close(&fx, "out.next_ldcfg", step(combine(cond, unc, &wc)), REL);
}

#[test]
fn ddpm_posterior_step() {
    let fx = Fixture::load("diffusion_ddpm");
    let dev = device::inference();
    let s = Schedule::edge();
    for t in [500usize, 1, 0] {
        let next = ddpm_step(
            &s,
            fx.tensor("in.x_t", &dev),
            fx.tensor("in.x0", &dev),
            t,
            fx.tensor("in.noise", &dev),
        );
        assert_close(&fx, &format!("out.t{t}"), next, REL);
    }
}

#[test]
fn pddm_residual_shift_forward_and_reverse() {
    let fx = Fixture::load("diffusion_pddm");
    let dev = device::inference();
    let cfg = ResidualShiftConfig {
        steps: fx.cfg_usize("steps"),
        kappa: fx.cfg_f64("kappa"),
        p: fx.cfg_f64("p"),
        eta_1: fx.cfg_f64("eta_1"),
        eta_t: fx.cfg_f64("eta_t"),
    };
    assert_eq!(
        cfg,
        ResidualShiftConfig::lodgepp(),
        "fixture uses the Lodge++ defaults"
    );
    let rs = cfg.init();
    assert_close(&fx, "out.eta", vec1(rs.eta.clone(), &dev), REL);
    let t: Vec<usize> = ints(&fx, "in.t").iter().map(|&t| t as usize).collect();
    let q = rs.q_sample(
        fx.tensor("in.d0", &dev),
        fx.tensor("in.dp", &dev),
        &t,
        fx.tensor("in.noise", &dev),
    );
    assert_close(&fx, "out.q_sample", q.clone(), REL);
    let step = rs.step(
        q,
        fx.tensor("in.x0", &dev),
        fx.cfg_usize("step_t"),
        fx.tensor("in.z", &dev),
    );
    assert_close(&fx, "out.step", step, REL);
}

#[test]
fn long_form_overwrite_and_stitch() {
    let fx = Fixture::load("diffusion_longform");
    let dev = device::inference();
    let over = overwrite_first_halves(fx.tensor("in.x", &dev));
    assert_close(&fx, "out.overwritten", over.clone(), REL);
    let rot6d = fx.config["rot6d"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r[0].as_u64().unwrap() as usize..r[1].as_u64().unwrap() as usize)
        .collect();
    let layout = ChannelLayout { rot6d };
    assert_close(&fx, "out.stitched", stitch(over, &layout), REL);
}

/// The stitcher's host-side 6D → matrix (the motion crate's `Mat3::from_6d`) agrees with the
/// tensor version used by the FK losses (`loss::rot6d_to_matrix`): one "first two rows" layout.
#[test]
fn stitch_rot6d_convention_matches_the_fk_loss() {
    let fx = Fixture::load("diffusion_longform");
    let dev = device::inference();
    let (shape, data) = fx.raw("in.x");
    let c = shape[2];
    let d6: Vec<f32> = data
        .chunks_exact(c)
        .flat_map(|row| row[1..7].to_vec())
        .collect();
    let n = d6.len() / 6;
    let tensor =
        loss::rot6d_to_matrix(Tensor::from_data(TensorData::new(d6.clone(), [n, 6]), &dev));
    let host: Vec<f32> = d6
        .chunks_exact(6)
        .flat_map(|d| {
            let d: [f64; 6] = std::array::from_fn(|k| f64::from(d[k]));
            Mat3::from_6d(&d)
                .0
                .into_iter()
                .flatten()
                .map(|v| v as f32)
                .collect::<Vec<f32>>()
        })
        .collect();
    let got: Vec<f32> = tensor
        .into_data()
        .convert::<f32>()
        .try_into_vec::<f32>()
        .unwrap();
    let err = got
        .iter()
        .zip(&host)
        .fold(0f32, |m, (a, b)| m.max((a - b).abs()));
    println!("rot6d host vs loss::rot6d_to_matrix: max abs err {err:.2e}");
    assert!(err < 1e-5, "6D conventions differ by {err}");
}
