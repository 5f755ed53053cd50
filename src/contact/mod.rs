//! Interface (contact) constitutive laws, behind the [`InterfaceLaw`] trait: the relation
//! between the relative displacement of the two faces of an interface element, paper
//! Eq. (26), u = (u_T, u_N) = ((u^B − u^A)·t, (u^B − u^A)·n), and the contact stresses
//! p = (p_T, p_N).
//!
//! Sign convention (paper): p_N < 0 in compression, u_N < 0 when the faces overlap (closure
//! −u_N > 0); n points from body A into body B.
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

/// d(p_T, p_N)/d(u_T, u_N): the (generally unsymmetric, paper Eq. 21) interface tangent.
pub type InterfaceTangent = SMatrix<f64, 2, 2>;

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
    /// Relative displacement (u_T, u_N), including the initial gap or interference.
    pub relative: [f64; 2],
    /// Contact stresses (p_T, p_N), p_N ≤ 0.
    pub stress: [f64; 2],
    /// Plastic (irreversible) slip u_T^p, paper Eq. (6), (10).
    pub plastic_slip: f64,
    /// Accumulated slip ū_T^p = Σ|Δu_T^p|, paper Eqs. (4), (17).
    pub accumulated_slip: f64,
    /// Largest closure reached so far (for unloading laws).
    pub max_closure: f64,
    /// Current friction coefficient μ_F.
    pub friction: f64,
    /// Current tangential and normal stiffness (k_T, k_N) in MPa/mm.
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
    /// Accumulated frictional dissipation per unit area, ∫ p_T du_T^p (N/mm), counting the
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
    /// Plastic slip Σ Δu_T^p of the closed increments since the cycle started (mm); open
    /// increments do not count (an open face carries no slip: the linear law's u_T^p
    /// follows it).
    pub cycle_slip: f64,
    /// Smallest and largest `cycle_slip` reached in the current cycle (mm).
    pub cycle_slip_range: [f64; 2],
    /// Largest |p_T| in the current cycle (MPa).
    pub cycle_max_shear: f64,
    /// Largest |p_N| (1/k_N + c_B) of the current cycle's increments at the closed point
    /// (mm), c_B the bodies' surface compliance at the point's element: the elastic closure
    /// of the interface and the bodies in series, which the cycle-jump stability limit is a
    /// fraction of.
    pub cycle_elastic_closure: f64,
    /// Results of the last completed cycle: dissipation per unit area (N/mm), slip amplitude
    /// (half the range of u_T^p, mm), largest |p_T| (MPa) and wear depth added (mm, A and B).
    pub last_cycle_dissipation: f64,
    pub last_cycle_slip_amplitude: f64,
    pub last_cycle_max_shear: f64,
    pub last_cycle_wear: [f64; 2],
}

impl PointHistory {
    /// The history after a law update from the committed state whose history is `self` to
    /// `trial` (stress p_{n+1}, plastic slip u_T^p), with `wear` the pair's wear model and
    /// `gap_wear` the wear the law saw, and `body_compliance` the compliance c_B of the
    /// bodies' surfaces in series with the interface (mm/MPa, for the elastic closure
    /// tracker). Backward Euler like the law: the dissipation
    /// increment is p_T,{n+1} Δu_T^p (exact for Coulomb at constant pressure, where p_T is
    /// constant during slip) and the wear increment is explicit in the trial stress.
    pub fn advanced(
        &self,
        committed_slip: f64,
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
        let slip = trial.plastic_slip - committed_slip;
        let [p_t, p_n] = trial.stress;
        h.dissipation += p_t * slip;
        h.cycle_slip += slip;
        h.cycle_slip_range = [
            h.cycle_slip_range[0].min(h.cycle_slip),
            h.cycle_slip_range[1].max(h.cycle_slip),
        ];
        h.cycle_max_shear = h.cycle_max_shear.max(p_t.abs());
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
    /// `relative` = (u_T, u_N), starting from the `committed` state.
    fn update(
        &self,
        relative: [f64; 2],
        committed: &InterfaceState,
    ) -> (InterfaceState, InterfaceTangent);

    /// The elastic (stick) tangent at `state`: diag(k_T, k_N) from the stiffnesses the law
    /// stored in the state, scaled to the regularising stiffness for an open point. It is
    /// symmetric positive definite, and is what the paper iterates with (conclusion 3,
    /// "elastic contact matrix"); asperity also uses it to precondition the unsymmetric
    /// consistent tangent.
    fn elastic_tangent(&self, state: &InterfaceState) -> InterfaceTangent {
        let k = InterfaceTangent::new(state.stiffness[0], 0.0, 0.0, state.stiffness[1]);
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

/// Whether a closed point sticks, given F = |p_T^trial| − μ|p_N| (paper Eq. 11) and the
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
    /// friction law, which drops the coupling ∂p_T/∂u_N and makes the tangent symmetric
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
                k[(0, 1)] = 0.0;
                k
            }
            ContactAlgorithm::ElasticContact => law.elastic_tangent(state),
        }
    }
}
