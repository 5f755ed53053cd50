//! Element sets: the [`ElementSet`] trait the assembler is generic over, and the model's two
//! sets, the continuum cells of the bodies and the interface elements of the contact pairs.

use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};

use super::continuum::{CellBody, CellHistory, CellTemperature, Formulation, evaluate_cell};
use super::interface6::{InterfaceElement, evaluate_interface};
use super::quadrature::{MAX_CELL_POINTS, cell_rule};
use super::{Analysis, ElementInput, ElementMatrix, ElementOutput, ElementVector};
use crate::contact::wear::WearModel;
use crate::contact::{InterfaceLaw, InterfaceState};
use crate::material::{Material, PointState};
use crate::mesh::CellKind;

/// A family of elements sharing a kernel and a kind of integration-point state (continuum
/// cells, interface elements, ...). The assembler is generic over this trait.
pub trait ElementSet: Sync {
    /// History stored per integration point.
    type State: Copy + Default + Send + Sync;

    /// Number of elements.
    fn len(&self) -> usize;

    /// Whether the set is empty.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Global node indices of element `e` (at most 8).
    fn nodes(&self, e: usize) -> &[u32];

    /// Displacement components per node, D ([`Analysis::dofs_per_node`]): element dof
    /// D·i + c is component c of node i, global dof D·n + c of node n.
    fn dofs_per_node(&self) -> usize;

    /// State slots per element; element `e` owns slots `e·P .. (e+1)·P`.
    fn points_per_element(&self) -> usize;

    /// Adds the internal force (and the tangent, if requested) of element `e` to `output`,
    /// updating its trial states from the committed ones in `input`.
    fn evaluate(
        &self,
        e: usize,
        input: &ElementInput<Self::State>,
        output: ElementOutput<Self::State>,
    );

    /// Whether the tangent of an element whose evaluation produced the trial states `trial`
    /// is its constant reference matrix ([`Self::reference_tangent`]), bit for bit — e.g. a
    /// cell none of whose points yielded has its elastic stiffness. Lets assembly keep such
    /// elements' matrices instead of re-evaluating them
    /// ([`GlobalSystem::assemble_reusing`](crate::assembly::GlobalSystem::assemble_reusing)).
    /// Default: never (the set has no reference matrix).
    fn tangent_is_reference(&self, _trial: &[Self::State]) -> bool {
        false
    }

    /// Adds the reference matrix of element `e` (see [`Self::tangent_is_reference`]) to `k`.
    /// Called only for sets whose [`Self::tangent_is_reference`] can be true; the default
    /// adds nothing, matching the default "never".
    fn reference_tangent(&self, _e: usize, _k: &mut ElementMatrix) {}
}

/// A continuum cell of the model with its node coordinates copied in (so assembly reads one
/// contiguous record per element).
#[derive(Clone, Copy, Debug)]
pub struct ContinuumCell {
    pub kind: CellKind,
    pub nodes: [u32; 8],
    pub coords: [[f64; 2]; 8],
    /// Index of the body (into [`Model::bodies`](crate::model::Model::bodies)).
    pub body: u32,
    /// Index of the cell in [`Mesh::cells`](crate::mesh::Mesh::cells).
    pub mesh_cell: u32,
}

/// All continuum cells of the model, with one material per body.
#[derive(Debug)]
pub struct ContinuumSet {
    pub analysis: Analysis,
    pub cells: Vec<ContinuumCell>,
    pub materials: Vec<Box<dyn Material>>,
    /// Element formulation of each body.
    pub formulations: Vec<Formulation>,
    /// Linear thermal expansion coefficient α (1/K) of each body (0: no thermal strain).
    pub expansions: Vec<f64>,
}

impl ElementSet for ContinuumSet {
    type State = PointState;

    fn len(&self) -> usize {
        self.cells.len()
    }

    fn nodes(&self, e: usize) -> &[u32] {
        let c = &self.cells[e];
        &c.nodes[..c.kind.node_count()]
    }

    fn dofs_per_node(&self) -> usize {
        self.analysis.dofs_per_node()
    }

    fn points_per_element(&self) -> usize {
        MAX_CELL_POINTS
    }

    fn evaluate(
        &self,
        e: usize,
        input: &ElementInput<PointState>,
        output: ElementOutput<PointState>,
    ) {
        self.evaluate_cell(e, None, None, input, output);
    }

    /// A point that did not yield got its material's elastic tangent (the [`Material`]
    /// contract of [`PointState::yielding`]).
    fn tangent_is_reference(&self, trial: &[PointState]) -> bool {
        !trial.iter().any(|s| s.yielding)
    }

    /// The elastic stiffness: the tangent at zero displacement from virgin states.
    fn reference_tangent(&self, e: usize, k: &mut ElementMatrix) {
        let virgin = [PointState::default(); MAX_CELL_POINTS];
        let mut scratch = virgin;
        let input = ElementInput {
            u: &ElementVector::zeros(),
            committed: &virgin,
            algorithm: Default::default(),
        };
        let output = ElementOutput {
            trial: &mut scratch,
            k: Some(k),
            f: None,
        };
        self.evaluate(e, &input, output);
    }
}

impl ContinuumSet {
    /// Evaluates cell `e` with its body's formulation and material, under its thermal
    /// eigenstrain and with its internal-variable history where it has them.
    fn evaluate_cell(
        &self,
        e: usize,
        temperature: Option<&CellTemperature>,
        history: Option<CellHistory>,
        input: &ElementInput<PointState>,
        output: ElementOutput<PointState>,
    ) {
        let c = &self.cells[e];
        let body = c.body as usize;
        evaluate_cell(
            &self.analysis,
            c.kind,
            &c.coords,
            CellBody {
                formulation: self.formulations[body],
                material: self.materials[body].as_ref(),
                temperature,
                history,
            },
            input,
            output,
        );
    }

    /// Whether cell `e`'s matrix may couple the in-plane displacements with the
    /// circumferential one (twist): not for a linear (isotropic elastic) body, whose
    /// tangent is block diagonal in (xx, yy, xy, zz | rθ, zθ); yes for a plastic one.
    pub fn couples_twist(&self, e: usize) -> bool {
        !self.materials[self.cells[e].body as usize].is_linear()
    }

    /// Whether every body's material is linear: the continuum stiffness is then constant
    /// (small strains) and its internal force is K_c · u.
    pub fn is_linear(&self) -> bool {
        self.materials.iter().all(|m| m.is_linear())
    }
}

/// Where each cell's internal variables (backstresses, [`Material::internal_variables`] per
/// point) lie in the flat internal-variable array of the continuum: the UMAT "STATEV" shape,
/// a cell's points one after the other. Cells of bodies without internal variables take no
/// room, and a model without any has an empty layout (no offsets at all).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InternalLayout {
    /// Start of every cell's range and the end of the last (empty without internal
    /// variables).
    offsets: Vec<usize>,
}

impl InternalLayout {
    /// The layout of `set`'s cells.
    pub fn new(set: &ContinuumSet) -> Self {
        if set.materials.iter().all(|m| m.internal_variables() == 0) {
            return Self::default();
        }
        let mut offsets = Vec::with_capacity(set.cells.len() + 1);
        let mut end = 0;
        offsets.push(end);
        for c in &set.cells {
            let stride = set.materials[c.body as usize].internal_variables();
            end += stride * cell_rule(c.kind).len();
            offsets.push(end);
        }
        Self { offsets }
    }

    /// Whether no cell has internal variables.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Length of the internal-variable array.
    pub fn len(&self) -> usize {
        self.offsets.last().copied().unwrap_or(0)
    }

    /// The range of cell `e`'s internal variables.
    pub fn range(&self, e: usize) -> Range<usize> {
        match self.offsets.get(e..e + 2) {
            Some(&[start, end]) => start..end,
            _ => 0..0,
        }
    }
}

/// The temperature change from the stress-free reference that drives the thermal strains:
/// per body a uniform change, or the nodal field (of the conduction solve).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TemperatureField {
    /// Per body: its uniform change, or `None` where it follows [`Self::nodal`]. Empty: no
    /// temperature anywhere.
    pub bodies: Vec<Option<f64>>,
    /// Per mesh node (read only for the bodies that follow it).
    pub nodal: Vec<f64>,
}

impl TemperatureField {
    /// The temperature change of cell `cell`'s nodes (its body's uniform value, or the nodal
    /// field), or `None` when there is no temperature.
    pub fn cell(&self, cell: &ContinuumCell) -> Option<[f64; 8]> {
        match self.bodies.get(cell.body as usize)? {
            Some(uniform) => Some([*uniform; 8]),
            None => {
                let mut t = [0.0; 8];
                for (t, &n) in t.iter_mut().zip(&cell.nodes[..cell.kind.node_count()]) {
                    *t = self.nodal.get(n as usize).copied().unwrap_or(0.0);
                }
                Some(t)
            }
        }
    }
}

/// The continuum cells in the context of one evaluation: the temperature field that drives
/// their thermal strains (eigenstrains, [`evaluate_cell`]) and, when some body has internal
/// variables (kinematic hardening), their committed values and the trial ones to write.
/// Tangents do not depend on the temperature, so the reference matrices are the set's.
#[derive(Debug)]
pub struct ContinuumInContext<'a> {
    pub set: &'a ContinuumSet,
    pub field: &'a TemperatureField,
    history: Option<SharedHistory<'a>>,
}

/// The continuum's internal variables during a parallel assembly. The trial values are
/// written by the element evaluations, each into its own cell's range, through atomic stores
/// (plain stores on the usual targets) so that no evaluation order can race.
#[derive(Debug)]
struct SharedHistory<'a> {
    layout: &'a InternalLayout,
    committed: &'a [f64],
    trial: &'a [AtomicU64],
}

/// Internal variables one cell holds at most: its points times the largest stride.
const MAX_CELL_INTERNAL: usize = MAX_CELL_POINTS * crate::material::MAX_INTERNAL_VARIABLES;

impl<'a> ContinuumInContext<'a> {
    /// The set under the temperature `field`, with its committed internal variables and the
    /// trial ones to write (both empty when `layout` is).
    pub fn new(
        set: &'a ContinuumSet,
        field: &'a TemperatureField,
        layout: &'a InternalLayout,
        committed: &'a [f64],
        trial: &'a mut [f64],
    ) -> Self {
        const { assert!(std::mem::align_of::<AtomicU64>() == std::mem::align_of::<f64>()) };
        assert_eq!(committed.len(), layout.len());
        assert_eq!(trial.len(), layout.len());
        let history = (!layout.is_empty()).then(|| {
            // SAFETY: AtomicU64 has the size of f64 and (checked above) its alignment, and
            // the exclusive borrow of `trial` for 'a makes these atomics its only access.
            let trial = unsafe {
                std::slice::from_raw_parts(trial.as_mut_ptr().cast::<AtomicU64>(), trial.len())
            };
            SharedHistory {
                layout,
                committed,
                trial,
            }
        });
        Self {
            set,
            field,
            history,
        }
    }

    /// Whether some body has internal variables.
    pub fn has_history(&self) -> bool {
        self.history.is_some()
    }
}

impl ElementSet for ContinuumInContext<'_> {
    type State = PointState;

    fn len(&self) -> usize {
        self.set.len()
    }

    fn nodes(&self, e: usize) -> &[u32] {
        self.set.nodes(e)
    }

    fn dofs_per_node(&self) -> usize {
        self.set.dofs_per_node()
    }

    fn points_per_element(&self) -> usize {
        MAX_CELL_POINTS
    }

    fn evaluate(
        &self,
        e: usize,
        input: &ElementInput<PointState>,
        output: ElementOutput<PointState>,
    ) {
        let set = self.set;
        let c = &set.cells[e];
        let body = c.body as usize;
        let temperature = self.field.cell(c).map(|nodal| CellTemperature {
            expansion: set.expansions[body],
            nodal,
        });
        let range = self.history.as_ref().map_or(0..0, |h| h.layout.range(e));
        let Some(h) = self.history.as_ref().filter(|_| !range.is_empty()) else {
            // No internal variables: no scratch to zero (it was a fifth of the memset of a
            // plain plastic run).
            set.evaluate_cell(e, temperature.as_ref(), None, input, output);
            return;
        };
        let mut trial = [0.0; MAX_CELL_INTERNAL];
        let trial = &mut trial[..range.len()];
        let history = CellHistory {
            committed: &h.committed[range.clone()],
            trial: &mut *trial,
        };
        set.evaluate_cell(e, temperature.as_ref(), Some(history), input, output);
        for (slot, value) in h.trial[range].iter().zip(trial.iter()) {
            slot.store(value.to_bits(), Ordering::Relaxed);
        }
    }

    fn tangent_is_reference(&self, trial: &[PointState]) -> bool {
        self.set.tangent_is_reference(trial)
    }

    fn reference_tangent(&self, e: usize, k: &mut ElementMatrix) {
        self.set.reference_tangent(e, k)
    }
}

/// A contact pair: its law, the wear of its surfaces, its interference and the range of its
/// elements in [`InterfaceSet::elements`].
#[derive(Debug)]
pub struct ContactPair {
    pub name: String,
    pub law: Box<dyn InterfaceLaw>,
    /// How the pair's surfaces wear (`None`: they do not).
    pub wear: Option<WearModel>,
    /// Initial interference δ in mm (positive: overlap).
    pub interference: f64,
    pub elements: std::ops::Range<usize>,
}

impl ContactPair {
    /// The wear model of the pair's surfaces, if they wear.
    pub fn wear(&self) -> Option<&WearModel> {
        self.wear.as_ref()
    }

    /// Short description for logs: the law, and the wear model if the surfaces wear.
    pub fn describe(&self) -> String {
        match &self.wear {
            Some(wear) => format!("{}; wear: {}", self.law.describe(), wear.describe()),
            None => self.law.describe(),
        }
    }
}

/// All interface elements of the model, pair after pair.
#[derive(Debug)]
pub struct InterfaceSet {
    pub analysis: Analysis,
    pub elements: Vec<InterfaceElement>,
    pub pairs: Vec<ContactPair>,
}

/// Integration points per interface element.
pub const INTERFACE_POINTS: usize = 3;

impl InterfaceSet {
    /// Position (on side B) of integration point `g` of element `e`.
    pub fn point_position(&self, e: usize, g: usize) -> [f64; 2] {
        let element = &self.elements[e];
        let (xi, w) = element.rule.points()[g];
        super::interface6::interface_point(&self.analysis, &element.b_coords, xi, w).x
    }
}

impl ElementSet for InterfaceSet {
    type State = InterfaceState;

    fn len(&self) -> usize {
        self.elements.len()
    }

    fn nodes(&self, e: usize) -> &[u32] {
        &self.elements[e].nodes
    }

    fn dofs_per_node(&self) -> usize {
        self.analysis.dofs_per_node()
    }

    fn points_per_element(&self) -> usize {
        INTERFACE_POINTS
    }

    fn evaluate(
        &self,
        e: usize,
        input: &ElementInput<InterfaceState>,
        output: ElementOutput<InterfaceState>,
    ) {
        let element = &self.elements[e];
        let pair = &self.pairs[element.pair as usize];
        let law = pair.law.as_ref();
        evaluate_interface(
            &self.analysis,
            element,
            pair.interference,
            law,
            pair.wear(),
            input,
            output,
        );
    }
}
