//! The guide's share `α` of a leaf's samples, learned by stochastic gradient descent.

use super::Record;

/// Learns the guide's share `α` of a leaf's samples by stochastic gradient descent (Adam) on
/// the Kullback–Leibler divergence from the mixture to the product `F = L_i f cosθ`, as in
/// Müller's 2019 follow-up ("Practical Path Guiding in Production", the authors'
/// `bsdfSamplingFractionLoss = kl`): with the BSDF fraction `s = σ(θ)` and mixture
/// `q = s·p_b + (1−s)·p_g`, `D(s) = −∫ (F/I) log q + const`, so a record `(F, p)` of a direction
/// drawn with pdf `p` gives `∂D/∂s ≈ −(F/q)(p_b − p_g) / p` (up to the constant `1/I`, which
/// Adam's normalisation removes); Adam moves `θ` against it (learning rate 0.01, L2 pull of
/// 0.01·θ toward `s = ½`, `θ` kept in ±20). The variance loss (`(F/q)²` in place of `F/q`) lost
/// 1.06× on the door at 10 s: it follows the rare large records. A leaf learns only while it
/// has a distribution to sample (before, the guide's pdf is a uniform stand-in that would teach
/// `α` to shun a guide that does not exist yet). Records arrive in a fixed order, so the learned
/// `α = 1 − σ(θ)` is deterministic too.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct FractionLearner {
    theta: f32,
    m: f32,
    v: f32,
    steps: i32,
    batch: f32,
    weight: f32,
}

impl FractionLearner {
    const RATE: f32 = 0.01;
    const BETA1: f32 = 0.9;
    const BETA2: f32 = 0.999;

    pub(super) fn alpha(&self) -> f32 {
        1.0 - 1.0 / (1.0 + (-self.theta).exp())
    }

    pub(super) fn learn(&mut self, r: &Record) {
        if !(r.product > 0.0 && r.pdf > 0.0) {
            return;
        }
        let s = 1.0 / (1.0 + (-self.theta).exp());
        let q = s * r.p_bsdf + (1.0 - s) * r.p_guide;
        let ratio = r.product / q;
        let d_s = -ratio / r.pdf * (r.p_bsdf - r.p_guide);
        let g = d_s * s * (1.0 - s) + 0.01 * self.theta;
        if !g.is_finite() {
            return;
        }
        self.batch += g;
        self.weight += 1.0;
        if self.weight > 1.0 {
            let g = self.batch / self.weight;
            self.batch = 0.0;
            self.weight = 0.0;
            self.steps += 1;
            let t = self.steps;
            let rate =
                Self::RATE * (1.0 - Self::BETA2.powi(t)).sqrt() / (1.0 - Self::BETA1.powi(t));
            self.m = Self::BETA1 * self.m + (1.0 - Self::BETA1) * g;
            self.v = Self::BETA2 * self.v + (1.0 - Self::BETA2) * g * g;
            self.theta = (self.theta - rate * self.m / (self.v.sqrt() + 1e-8)).clamp(-20.0, 20.0);
        }
    }
}
