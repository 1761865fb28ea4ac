//! libtorch is linked, loads at run time through the rpath, and autograd works.
use tch::{nn, nn::Module, Device, Kind, Tensor};

#[test]
fn forward_and_backward_on_cpu_match_hand_computed_gradients() {
    // y = sum((w x + b)^2) with w = 2, b = 1, x = [1, 2, 3]:
    // dy/dw = sum(2 (w x + b) x) = 2 (3*1 + 5*2 + 7*3) = 68, dy/db = 2 (3 + 5 + 7) = 30.
    let vs = nn::VarStore::new(Device::Cpu);
    let mut lin = nn::linear(vs.root(), 1, 1, Default::default());
    tch::no_grad(|| {
        let _ = lin.ws.fill_(2.0);
        let _ = lin.bs.as_mut().unwrap().fill_(1.0);
    });
    let x = Tensor::from_slice(&[1.0f32, 2.0, 3.0]).view([3, 1]);
    let y = lin.forward(&x).pow_tensor_scalar(2).sum(Kind::Float);
    assert_eq!(y.double_value(&[]), 9.0 + 25.0 + 49.0);
    y.backward();
    assert_eq!(lin.ws.grad().double_value(&[0, 0]), 68.0);
    assert_eq!(lin.bs.as_ref().unwrap().grad().double_value(&[0]), 30.0);
}

#[test]
fn small_network_trains_on_cpu() {
    // Two-layer MLP fits XOR: a real optimisation loop through libtorch.
    tch::manual_seed(0);
    let vs = nn::VarStore::new(Device::Cpu);
    let net = nn::seq()
        .add(nn::linear(vs.root() / "l1", 2, 16, Default::default()))
        .add_fn(|x| x.tanh())
        .add(nn::linear(vs.root() / "l2", 16, 1, Default::default()));
    let mut opt = nn::OptimizerConfig::build(nn::Adam::default(), &vs, 0.05).unwrap();
    let x = Tensor::from_slice(&[0.0f32, 0., 0., 1., 1., 0., 1., 1.]).view([4, 2]);
    let t = Tensor::from_slice(&[0.0f32, 1., 1., 0.]).view([4, 1]);
    let mut loss = f64::INFINITY;
    for _ in 0..500 {
        let l = net.forward(&x).mse_loss(&t, tch::Reduction::Mean);
        opt.backward_step(&l);
        loss = l.double_value(&[]);
    }
    assert!(loss < 1e-3, "XOR loss stayed at {loss}");
}
