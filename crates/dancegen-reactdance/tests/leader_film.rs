//! The optional per-token leader FiLM (`DenoiserConfig::leader_film`, ours): the follower
//! token at time `n` is modulated by the leader token at `n`, and only by it, before any
//! attention; without the key the network is the paper's.

use dancegen_nn::burn::tensor::{Distribution, Tensor};
use dancegen_nn::device;
use dancegen_reactdance::config::{DenoiserConfig, leader_token_dim, music_token_dim};
use dancegen_reactdance::denoiser::{DuetCond, Layout};

fn config(leader_film: bool) -> DenoiserConfig {
    DenoiserConfig {
        d_model: 32,
        n_layers: 1,
        n_heads: 4,
        d_ff: 64,
        // No leader encoder layer: an encoded leader token is then a function of that token
        // alone, so a change of one leader token may change one FiLM vector only.
        leader_layers: 0,
        dropout: 0.0,
        block_tokens: 6,
        causal: false,
        timesteps: 100,
        leader_film,
    }
}

/// Largest |a − b| of each token of two `[1, N, d]` tensors.
fn per_token_diff(a: Tensor<3>, b: Tensor<3>) -> Vec<f32> {
    let [_, n, d] = a.dims();
    let v = (a - b).abs().into_data().try_to_vec::<f32>().unwrap();
    (0..n)
        .map(|t| v[t * d..(t + 1) * d].iter().copied().fold(0.0, f32::max))
        .collect()
}

#[test]
fn a_leader_token_modulates_the_follower_token_of_its_time_only() {
    let dev = device::inference();
    dev.seed(5);
    let (c, f, n, changed) = (12, 4, 6, 3);
    let normal = Distribution::Normal(0.0, 1.0);
    let leader = Tensor::<3>::random([1, n, leader_token_dim(f)], normal, &dev);
    let music = Tensor::<3>::random([1, n, music_token_dim(f)], normal, &dev);
    let bump = Tensor::<3>::random([1, 1, leader_token_dim(f)], normal, &dev);
    let other_leader = leader.clone().slice_assign(
        [0..1, changed..changed + 1, 0..leader_token_dim(f)],
        leader
            .clone()
            .slice([0..1, changed..changed + 1, 0..leader_token_dim(f)])
            + bump,
    );
    let a = DuetCond {
        leader,
        music: music.clone(),
    };
    let b = DuetCond {
        leader: other_leader,
        music,
    };
    for leader_film in [false, true] {
        let net = config(leader_film).init(c, f, &dev);
        assert_eq!(net.leader_film.is_some(), leader_film);
        let pa = net.prepare(&a, &[true], Layout::Batched, false);
        let pb = net.prepare(&b, &[true], Layout::Batched, false);
        let diff = per_token_diff(pa.music, pb.music);
        for (t, d) in diff.iter().enumerate() {
            if leader_film && t == changed {
                assert!(
                    *d > 1e-3,
                    "token {t}: the changed leader token left its FiLM as is"
                );
            } else {
                assert!(
                    *d == 0.0,
                    "leader FiLM {leader_film}, token {t}: the FiLM changed by {d}"
                );
            }
        }
        // The null branch is one vector, whatever the leader.
        let na = net.prepare(&a, &[false], Layout::Batched, false);
        let nb = net.prepare(&b, &[false], Layout::Batched, false);
        assert_eq!(na.music.dims(), [1, 1, 32]);
        assert_eq!(per_token_diff(na.music, nb.music), vec![0.0]);
    }
}

#[test]
fn a_bundle_without_the_key_is_the_papers_network() {
    let c: DenoiserConfig = toml::from_str("d_model = 32\nn_heads = 4").unwrap();
    assert!(!c.leader_film);
    let c: DenoiserConfig = toml::from_str("leader_film = true").unwrap();
    assert!(c.leader_film);
}

/// A bundle whose `model.toml` disagrees with its weights about the key does not load, and
/// the error names the weights file once and the tensors that do not fit.
#[test]
fn weights_trained_with_the_film_do_not_load_into_the_papers_network() {
    use dancegen_reactdance::bundle::DuetModel;
    let shipped =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/reactdance-small");
    let dir = tempfile::tempdir().unwrap();
    for f in [
        "hfsq.safetensors",
        "denoiser.safetensors",
        "normalizer.json",
    ] {
        std::fs::copy(shipped.join(f), dir.path().join(f)).unwrap();
    }
    let toml = std::fs::read_to_string(shipped.join("model.toml")).unwrap();
    assert!(
        toml.contains("leader_film = true"),
        "the shipped model uses the key"
    );
    let paper = toml.replace("leader_film = true", "leader_film = false");
    std::fs::write(dir.path().join("model.toml"), paper).unwrap();
    let Err(e) = DuetModel::load(dir.path(), &device::inference()) else {
        panic!("weights with the FiLM loaded into the paper's network");
    };
    let msg = e.to_string();
    let file = dir
        .path()
        .join("denoiser.safetensors")
        .display()
        .to_string();
    assert_eq!(msg.matches(&file).count(), 1, "{msg}");
    assert!(
        msg.contains("tensors the model does not have: leader_film.bias, leader_film.weight"),
        "{msg}"
    );
}
