//! Losses against PyTorch formulas (`tools/parity/gpt.py`, fixture `losses`) and the
//! differentiable FK against the motion crate's CPU FK (an independent implementation).

mod common;

use common::{Fixture, assert_close};
use dancegen_motion::fk::{LocalRotations, forward_kinematics as cpu_fk};
use dancegen_motion::rotation::Mat3;
use dancegen_motion::skeleton::Skeleton;
use dancegen_nn::burn::tensor::{Tensor, TensorData};
use dancegen_nn::device;
use dancegen_nn::loss::{
    self, Distance, FkSkeleton, forward_kinematics, hinge_discriminator, hinge_generator,
    rot6d_to_matrix,
};

const REL: f64 = 1e-5;

#[test]
fn formulas_match_pytorch() {
    let fx = Fixture::load("losses");
    let dev = device::inference();
    assert_close(
        &fx,
        "out.matrix",
        rot6d_to_matrix(fx.tensor("in.d6", &dev)),
        REL,
    );
    let nce = loss::info_nce(
        fx.tensor("in.a", &dev),
        fx.tensor("in.b", &dev),
        fx.cfg_f64("temperature"),
    );
    assert_close(&fx, "out.info_nce", nce, REL);
    let (p, q) = (fx.tensor::<3>("in.p", &dev), fx.tensor::<3>("in.q", &dev));
    assert_close(
        &fx,
        "out.smooth_l1",
        loss::reconstruction(p.clone(), q.clone(), Distance::SmoothL1),
        REL,
    );
    assert_close(
        &fx,
        "out.velocity_l2",
        loss::velocity(p.clone(), q.clone(), Distance::L2),
        REL,
    );
    assert_close(
        &fx,
        "out.acceleration_l1",
        loss::acceleration(p, q, Distance::L1),
        REL,
    );
}

#[test]
fn differentiable_fk_equals_the_motion_crate_fk() {
    let dev = device::inference();
    let (frames, joints) = (4usize, 24usize);
    // Deterministic "random" axis-angles up to ~1 rad and a moving root.
    let aa: Vec<f64> = (0..frames * joints * 3)
        .map(|i| (i as f64 * 0.7311).sin() * 0.9)
        .collect();
    let root: Vec<f64> = (0..frames * 3).map(|i| 0.1 * i as f64).collect();
    let skel = Skeleton::smpl24();
    let want = cpu_fk(&skel, LocalRotations::AxisAngle(&aa), &root, false)
        .unwrap()
        .positions;
    let mats: Vec<f32> = aa
        .chunks_exact(3)
        .flat_map(|v| {
            let m = Mat3::from_axis_angle([v[0], v[1], v[2]]);
            m.0.into_iter().flatten().map(|x| x as f32)
        })
        .collect();
    let rot = Tensor::<4>::from_data(TensorData::new(mats, [frames, joints, 3, 3]), &dev);
    let rootf: Vec<f32> = root.iter().map(|&v| v as f32).collect();
    let root_t = Tensor::<2>::from_data(TensorData::new(rootf, [frames, 3]), &dev);
    let got: Vec<f32> = forward_kinematics(rot, root_t, &FkSkeleton::smpl24())
        .into_data()
        .try_into_vec::<f32>()
        .unwrap();
    let err = got
        .iter()
        .zip(&want)
        .map(|(&a, &b)| (f64::from(a) - b).abs())
        .fold(0.0, f64::max);
    println!("FK: max abs error {err:.2e} m");
    assert!(
        err < 1e-5,
        "differentiable FK differs from the CPU FK by {err} m"
    );
}

#[test]
fn fk_gradients_flow_to_the_rotations() {
    let dev = device::training();
    let d6 = Tensor::<2>::from_data(
        TensorData::new(
            (0..24 * 6)
                .map(|i| ((i as f32) * 0.37).cos())
                .collect::<Vec<f32>>(),
            [24, 6],
        ),
        &dev,
    )
    .require_grad();
    let rot = rot6d_to_matrix(d6.clone()).reshape([1, 24, 3, 3]);
    let pos = forward_kinematics(rot, Tensor::zeros([1, 3], &dev), &FkSkeleton::smpl24());
    let grads = pos.powf_scalar(2.0).sum().backward();
    let g = d6.grad(&grads).expect("gradient reaches the 6D input");
    let norm = g.abs().sum().into_scalar::<f32>();
    assert!(norm.is_finite() && norm > 0.0);
}

#[test]
fn gan_hinge_losses() {
    let dev = device::inference();
    let real = Tensor::<2>::from_data(TensorData::new(vec![2.0f32, 0.5], [2, 1]), &dev);
    let fake = Tensor::<2>::from_data(TensorData::new(vec![-2.0f32, 0.5], [2, 1]), &dev);
    // relu(1-2)=0, relu(1-0.5)=0.5 → 0.25; relu(1-2)=0, relu(1+0.5)=1.5 → 0.75.
    let d = hinge_discriminator(real, fake.clone()).into_scalar::<f32>();
    assert!((d - 1.0).abs() < 1e-6, "{d}");
    let g = hinge_generator(fake).into_scalar::<f32>();
    assert!((g - 0.75).abs() < 1e-6, "{g}");
}

#[test]
fn foot_contact_counts_only_contact_frames() {
    let dev = device::inference();
    // One foot moving 1 unit per frame along x for 3 frames; contact only on frame 0.
    let feet: Vec<f32> = (0..3).flat_map(|t| [t as f32, 0.0, 0.0]).collect();
    let feet = Tensor::<4>::from_data(TensorData::new(feet, [1, 3, 1, 3]), &dev);
    let contact = Tensor::<3>::from_data(TensorData::new(vec![1.0f32, 0.0, 1.0], [1, 3, 1]), &dev);
    // Steps 0→1 (contact) and 1→2 (none): squared velocity 1 on 1 of 6 entries.
    let l = loss::foot_contact(feet, contact, 0.95).into_scalar::<f32>();
    assert!((l - 1.0 / 6.0).abs() < 1e-6, "{l}");
}
