//! Interface (contact) constitutive laws, behind the [`InterfaceLaw`] trait: the relation
//! between the relative displacement of the two faces of an interface element, paper
//! Eq. (26), u = (u_T, u_N) = ((u^B − u^A)·t, (u^B − u^A)·n), and the contact stresses
//! p = (p_T, p_N).
//!
//! Sign convention (paper): p_N < 0 in compression, u_N < 0 when the faces overlap (closure
//! −u_N > 0); n points from body A into body B.
//!
//! **Two tangential directions (axisymmetry with twist).** The faces can also slide along
//! the circumference: u_θ = u_θ^B − u_θ^A, with the shear p_θ. The paper's laws are written
//! for one tangential direction; asperity extends them isotropically, so that its
//! Eqs. (4)–(11) hold for the tangential *vectors* u_τ = (u_T, u_θ) and p_τ = (p_T, p_θ):
//! the stick stiffness k_T acts in both directions, the slip condition F = |p_τ| + μ p_N ≤ 0
//! (Eq. 11 with |p_T| the length of the vector) is a circle in the (p_T, p_θ) plane, the
//! slip increment follows the trial shear (the non-associated flow of Eqs. 8–10 made
//! radial: Δu_τ^p = Δλ p_τ^tr / |p_τ^tr|, Δu_N^p = 0) and the accumulated slip that drives the
//! slip hardening of Eq. (4) is the length of the slip path, ū = ∫ |du_τ^p| (Eq. 17). The
//! return map is the radial return of Box 1 on that circle; the consistent tangent of Eq. (21)
//! gains the term μ|p_N| k_T/|p_τ^tr| (I − n nᵀ) of the turning direction n = p_τ^tr/|p_τ^tr|.
//! Vectors are ordered (T, N, θ), so that the indices 0 and 1 are those of the plane laws;
//! without twist the θ entries are zero, and every formula reduces exactly (bit for bit) to
//! the scalar one: |(x, 0)| = |x| and n = (sign x, 0).
//!
//! Like bulk materials, laws are pure functions of the relative displacement and the state
//! committed at the last converged step; the solver commits trial states only after a step
//! converged.

pub mod laws;
pub mod linear;
pub mod rough;
pub mod wear;

use nalgebra::SMatrix;
use serde::Deserialize;

use wear::WearModel;

/// d(p_T, p_N, p_θ)/d(u_T, u_N, u_θ): the (generally unsymmetric, paper Eq. 21) interface
/// tangent. Without twist only its leading 2×2 block is used.
pub type InterfaceTangent = SMatrix<f64, 3, 3>;

/// Index of the meridional (in-plane) tangential component of the interface vectors.
pub const MERIDIONAL: usize = 0;
/// Index of the normal component.
pub const NORMAL: usize = 1;
/// Index of the circumferential component (zero without twist).
pub const CIRCUMFERENTIAL: usize = 2;

/// The tangential part (T, θ) of an interface vector (T, N, θ).
#[inline]
pub fn tangential(v: [f64; 3]) -> [f64; 2] {
    [v[MERIDIONAL], v[CIRCUMFERENTIAL]]
}

/// Length of a tangential vector (T, θ). Exactly |v_T| when v_θ = 0 (hypot(x, ±0) = |x|, C99
/// Annex F), so the plane laws' numbers are unchanged.
#[inline]
pub fn length(v: [f64; 2]) -> f64 {
    v[0].hypot(v[1])
}

/// Dot product of two tangential vectors.
#[inline]
pub fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// Unit direction of the tangential vector `v` (of length `norm`): exactly (sign v_T, 0) when
/// v_θ = 0, as the scalar laws' sign(p_T^tr) (`signum`: +1 for +0).
#[inline]
pub fn direction(v: [f64; 2], norm: f64) -> [f64; 2] {
    if v[1] == 0.0 {
        [v[0].signum(), 0.0]
    } else {
        [v[0] / norm, v[1] / norm]
    }
}

/// The diagonal tangent diag(k_T, k_N, k_T) of stiffnesses [k_T, k_N].
#[inline]
pub fn diagonal_tangent(stiffness: [f64; 2]) -> InterfaceTangent {
    let [kt, kn] = stiffness;
    InterfaceTangent::from_diagonal(&nalgebra::Vector3::new(kt, kn, kt))
}

/// The interface tangent of a slipping point with radial return on the friction circle:
/// tangential block a n nᵀ + b (I − n nᵀ) (a along the slip direction n, b across it, the
/// turning of the direction) and the column ∂p_τ/∂u_N = `normal_coupling` (T, θ), with
/// ∂p_N/∂u_N = `kn` and ∂p_N/∂u_τ = 0 (Δu_N^p = 0, Eq. 10).
pub fn slip_tangent(
    n: [f64; 2],
    along: f64,
    across: f64,
    normal_coupling: [f64; 2],
    kn: f64,
) -> InterfaceTangent {
    let (t, c) = (MERIDIONAL, CIRCUMFERENTIAL);
    let mut k = InterfaceTangent::zeros();
    for (i, a) in [(0, t), (1, c)] {
        for (j, b) in [(0, t), (1, c)] {
            let identity = if i == j { 1.0 } else { 0.0 };
            k[(a, b)] = along * n[i] * n[j] + across * (identity - n[i] * n[j]);
        }
    }
    k[(t, NORMAL)] = normal_coupling[0];
    k[(c, NORMAL)] = normal_coupling[1];
    k[(NORMAL, NORMAL)] = kn;
    k
}

/// State of one interface integration point.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum ContactStatus {
    /// The faces are apart: no stress.
    #[default]
    Open = 0,
    /// Closed, tangential behaviour elastic (F < 0, paper Eq. 11).
    Stick = 1,
    /// Closed and slipping (F = 0).
    Slip = 2,
}

/// History and results at one interface integration point.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct InterfaceState {
    /// Relative displacement (u_T, u_N, u_θ), including the initial gap or interference in
    /// u_N; u_θ = 0 without twist.
    pub relative: [f64; 3],
    /// Contact stresses (p_T, p_N, p_θ), p_N ≤ 0; p_θ = 0 without twist.
    pub stress: [f64; 3],
    /// Plastic (irreversible) slip (u_T^p, u_θ^p), paper Eqs. (6), (10); u_θ^p = 0 without
    /// twist.
    pub plastic_slip: [f64; 2],
    /// Accumulated slip, the length of the slip path ū = Σ|Δu_τ^p|, paper Eqs. (4), (17).
    pub accumulated_slip: f64,
    /// Largest closure reached so far (for unloading laws).
    pub max_closure: f64,
    /// Current friction coefficient μ_F.
    pub friction: f64,
    /// Current tangential and normal stiffness (k_T, k_N) in MPa/mm (k_T in both tangential
    /// directions).
    pub stiffness: [f64; 2],
    pub status: ContactStatus,
    /// Whether the interface tangent used at this point in the last evaluation was
    /// unsymmetric (∂p_T/∂u_N ≠ ∂p_N/∂u_T: slip with friction, Eq. 21, or a shear stiffness
    /// that depends on the pressure, Eq. 3). Set by the element, not by the law.
    pub unsymmetric: bool,
    /// Cyclic-loading (fretting) and wear history of the point; kept by the element, not by
    /// the law.
    pub history: PointHistory,
}

/// What cyclic loading leaves at one interface point: frictional dissipation, wear depth and
/// the trackers of the current load cycle (a non-cyclic step counts as one cycle).
///
/// The element advances it after every law update ([`PointHistory::advanced`]); the cycle
/// hooks of [`crate::solver::cycles`] close and restart the cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PointHistory {
    /// Accumulated frictional dissipation per unit area, ∫ p_τ·du_τ^p (N/mm), counting the
    /// cycles a wear jump stands for.
    pub dissipation: f64,
    /// Wear depth (mm) of the surface of body A and of body B; their sum opens the gap.
    pub wear: [f64; 2],
    /// The wear h_A + h_B the law saw in this state's update (the committed wear at the
    /// start of the increment): `InterfaceState::relative[1]` includes it, so the
    /// kinematic normal displacement of the faces is `relative[1] − gap_wear`.
    pub gap_wear: f64,
    /// `dissipation` and `wear` when the current cycle started.
    pub cycle_start_dissipation: f64,
    pub cycle_start_wear: [f64; 2],
    /// Plastic slip Σ Δu_τ^p (T, θ) of the closed increments since the cycle started (mm);
    /// open increments do not count (an open face carries no slip: the linear law's u_τ^p
    /// follows it).
    pub cycle_slip: [f64; 2],
    /// The two ends of the cycle's slip path so far: the pair of its points (values of
    /// `cycle_slip`) farthest apart, kept by [`extend_slip_ends`] (mm).
    pub cycle_slip_ends: [[f64; 2]; 2],
    /// Largest |p_τ| in the current cycle (MPa).
    pub cycle_max_shear: f64,
    /// Largest |p_N| (1/k_N + c_B) of the current cycle's increments at the closed point
    /// (mm), c_B the bodies' surface compliance at the point's element: the elastic closure
    /// of the interface and the bodies in series, which the cycle-jump stability limit is a
    /// fraction of.
    pub cycle_elastic_closure: f64,
    /// Results of the last completed cycle: dissipation per unit area (N/mm), slip amplitude
    /// (half the extent of the cycle's slip path, the distance between its `cycle_slip_ends`:
    /// half the range of u_T^p without twist; mm), largest |p_τ| (MPa) and wear depth added
    /// (mm, A and B).
    pub last_cycle_dissipation: f64,
    pub last_cycle_slip_amplitude: f64,
    pub last_cycle_max_shear: f64,
    pub last_cycle_wear: [f64; 2],
}

impl PointHistory {
    /// The history after a law update from the committed state whose history is `self` and
    /// plastic slip `committed_slip` to `trial` (stress p_{n+1}, plastic slip u_τ^p), with
    /// `wear` the pair's wear model and `gap_wear` the wear the law saw, and
    /// `body_compliance` the compliance c_B of the bodies' surfaces in series with the
    /// interface (mm/MPa, for the elastic closure tracker). Backward Euler like the law: the
    /// dissipation increment is p_τ,{n+1}·Δu_τ^p (exact for Coulomb at constant pressure,
    /// where p_τ is constant during a straight slip) and the wear increment is explicit in
    /// the trial stress.
    pub fn advanced(
        &self,
        committed_slip: [f64; 2],
        trial: &InterfaceState,
        wear: Option<&WearModel>,
        gap_wear: f64,
        body_compliance: f64,
    ) -> Self {
        let mut h = *self;
        h.gap_wear = gap_wear;
        if trial.status == ContactStatus::Open {
            return h;
        }
        let slip = [
            trial.plastic_slip[0] - committed_slip[0],
            trial.plastic_slip[1] - committed_slip[1],
        ];
        let shear = tangential(trial.stress);
        let p_n = trial.stress[NORMAL];
        h.dissipation += dot(shear, slip);
        h.cycle_slip = [h.cycle_slip[0] + slip[0], h.cycle_slip[1] + slip[1]];
        h.cycle_slip_ends = extend_slip_ends(h.cycle_slip_ends, h.cycle_slip);
        h.cycle_max_shear = h.cycle_max_shear.max(length(shear));
        if trial.stiffness[1] > 0.0 {
            let closure = p_n.abs() * (1.0 / trial.stiffness[1] + body_compliance);
            h.cycle_elastic_closure = h.cycle_elastic_closure.max(closure);
        }
        if let Some(w) = wear {
            let dh = w.increment(trial.stress, slip);
            h.wear = [h.wear[0] + dh[0], h.wear[1] + dh[1]];
        }
        h
    }

    /// Total wear depth h_A + h_B (mm).
    pub fn depth(&self) -> f64 {
        self.wear[0] + self.wear[1]
    }

    /// Half the extent of the current cycle's slip path (mm): the slip amplitude the cycle
    /// would have if it ended now.
    pub fn cycle_slip_amplitude(&self) -> f64 {
        let [p, q] = self.cycle_slip_ends;
        0.5 * length([q[0] - p[0], q[1] - p[1]])
    }
}

/// The ends of a slip path whose ends so far are `ends` = [p, q], after it reached `x`:
/// a streaming estimate of the pair of the path's points farthest apart (its diameter).
/// A point beyond q along p → q (or beyond p) replaces that end; a point between them
/// replaces the nearer end when it lies farther from the other end than p from q. Exact for
/// a path on a straight line in any direction (reciprocating fretting, and the one
/// tangential direction of a plane model, where [p, q] are the smallest and largest slip)
/// and for a circle traced from its start; never longer than the true extent.
pub fn extend_slip_ends(ends: [[f64; 2]; 2], x: [f64; 2]) -> [[f64; 2]; 2] {
    let [p, q] = ends;
    let sub = |a: [f64; 2], b: [f64; 2]| [a[0] - b[0], a[1] - b[1]];
    let span = sub(q, p);
    if dot(sub(x, q), span) > 0.0 {
        return [p, x];
    }
    if dot(sub(x, p), span) < 0.0 {
        return [x, q];
    }
    let (from_p, from_q) = (length(sub(x, p)), length(sub(x, q)));
    if from_p.max(from_q) > length(span) {
        if from_p >= from_q { [p, x] } else { [x, q] }
    } else {
        ends
    }
}

impl InterfaceState {
    /// Whether the point's tangent couples shear and normal approach unsymmetrically.
    pub fn has_unsymmetric_tangent(&self) -> bool {
        self.unsymmetric
    }
}

/// An interface constitutive law.
pub trait InterfaceLaw: Send + Sync + std::fmt::Debug {
    /// Contact stresses, new state and consistent tangent for the relative displacement
    /// `relative` = (u_T, u_N, u_θ) (u_θ = 0 without twist), starting from the `committed`
    /// state.
    fn update(
        &self,
        relative: [f64; 3],
        committed: &InterfaceState,
    ) -> (InterfaceState, InterfaceTangent);

    /// The elastic (stick) tangent at `state`: diag(k_T, k_N, k_T) from the stiffnesses the
    /// law stored in the state, scaled to the regularising stiffness for an open point. It
    /// is symmetric positive definite, and is what the paper iterates with (conclusion 3,
    /// "elastic contact matrix"); asperity also uses it to precondition the unsymmetric
    /// consistent tangent.
    fn elastic_tangent(&self, state: &InterfaceState) -> InterfaceTangent {
        let k = diagonal_tangent(state.stiffness);
        if state.status == ContactStatus::Open {
            k * OPEN_TANGENT_FRACTION
        } else {
            k
        }
    }

    /// Whether a closed, sticking point carries tangential stress (friction and a
    /// tangential stiffness): it then holds its two faces against each other along the
    /// contact too, not only normal to it (the model's rigid-body check).
    fn carries_shear(&self) -> bool;

    /// Short description for logs.
    fn describe(&self) -> String;
}

/// Whether a closed point sticks, given F = |p_τ^trial| − μ|p_N| (paper Eq. 11) and the
/// friction limit μ|p_N|. Status stabilisation: a point that slipped in the last converged
/// increment and whose trial stress lies on the cone (within [`ON_CONE`] of the limit, as
/// every such point does at the start of the next increment, since the converged stress is
/// the trial stress of an unchanged displacement) stays on the slip branch. Its stress is
/// the same on either branch, but continued loading moves it along the slip branch, and the
/// slip tangent spares the iteration in which a stiff k_T would push it far outside the cone.
pub fn sticks(f: f64, limit: f64, committed: &InterfaceState) -> bool {
    if committed.status == ContactStatus::Slip {
        f < -ON_CONE * limit
    } else {
        f <= 0.0
    }
}

/// Relative tolerance of "on the friction cone" for [`sticks`]: round-off of the trial stress.
pub const ON_CONE: f64 = 1e-10;

/// Relative size of the stiffness an open point keeps in the tangent (never in the stress),
/// so that a body touching others only through open contact still has a regular matrix in
/// the first iteration; the residual uses the true zero stress, so the converged answer is
/// unaffected.
pub const OPEN_TANGENT_FRACTION: f64 = 1e-9;

/// The global solution algorithm for contact (paper §2.4 and conclusions 2–3). All three
/// evaluate the same residual, so they converge to the same solution; they differ in the
/// interface tangent used to compute the corrections.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactAlgorithm {
    /// Full Newton with the consistent, unsymmetric tangent (Eq. 21): quadratic convergence.
    #[default]
    Newton,
    /// The paper's two-step scheme: the normal contact stress is taken as known in the
    /// friction law, which drops the coupling ∂p_τ/∂u_N and makes the tangent symmetric
    /// (§2.4 end, conclusion 2); the normal problem keeps its full tangent.
    TwoStep,
    /// Iterations with the elastic contact matrix diag(k_T, k_N) (conclusion 3): symmetric
    /// and stable, but only linearly convergent once points slip.
    ElasticContact,
}

impl ContactAlgorithm {
    /// The interface tangent this algorithm uses at `state`, given the law's consistent one.
    pub fn tangent(
        self,
        law: &dyn InterfaceLaw,
        state: &InterfaceState,
        consistent: InterfaceTangent,
    ) -> InterfaceTangent {
        match self {
            ContactAlgorithm::Newton => consistent,
            ContactAlgorithm::TwoStep => {
                let mut k = consistent;
                k[(MERIDIONAL, NORMAL)] = 0.0;
                k[(CIRCUMFERENTIAL, NORMAL)] = 0.0;
                k
            }
            ContactAlgorithm::ElasticContact => law.elastic_tangent(state),
        }
    }
}
