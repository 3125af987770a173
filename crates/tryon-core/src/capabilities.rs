//! What a collider declares it can do beyond the `Collider` trait's required methods.

/// What a collider can do beyond moving points out and probing them. Every collider says which
/// of these it has ([`Collider::capabilities`]), so a stage that needs one knows it is missing
/// (and `tryon check` says so) instead of getting the trait's empty default.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Capabilities {
    /// [`Collider::focus`]: leaves out of its work the body far from the cloth.
    pub focus: bool,
    /// [`Collider::probe_opposite`]: the surface across a pinch.
    pub pinch: bool,
    /// [`Collider::sweep`]: continuous collision over a step.
    pub sweep: bool,
    /// [`Collider::pokes`]: body vertices under cloth triangles.
    pub pokes: bool,
    /// [`Collider::probe`]'s distances are the true distances to the body surface the swept
    /// test uses, so a point moving less than its distance cannot reach the still body.
    pub exact_distance: bool,
}

impl Capabilities {
    /// None of them: the trait's defaults.
    pub const NONE: Capabilities = Capabilities {
        focus: false,
        pinch: false,
        sweep: false,
        pokes: false,
        exact_distance: false,
    };

    /// The names of the capabilities `wanted` has and `self` lacks.
    pub fn missing(self, wanted: Capabilities) -> Vec<&'static str> {
        [
            (wanted.focus && !self.focus, "focus"),
            (wanted.pinch && !self.pinch, "pinch search"),
            (wanted.sweep && !self.sweep, "swept test"),
            (wanted.pokes && !self.pokes, "pokes"),
        ]
        .into_iter()
        .filter_map(|(lacks, name)| lacks.then_some(name))
        .collect()
    }
}
