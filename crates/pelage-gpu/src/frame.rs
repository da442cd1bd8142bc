//! The frame as a list of passes over named resources (vello's model): each stage
//! declares the passes its `encode` records, in order, and the resources each reads and
//! writes; a [`FramePlan`] strings the stages together and checks, once, that every
//! resource a pass reads was written by an earlier pass or is an input of the frame.
//!
//! Names are dotted paths: `mesh.positions`, `strands.vertices`, `shadow0.volume`,
//! `visibility`, `target.color`. The plan checks order, not contents: it is what an
//! engine splicing pelage's passes into its own render graph reads to know what must
//! come before what, and what the facade checks its own order against.

/// One pass a stage records: its label (the one its GPU timestamps carry) and the named
/// resources it reads and writes.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PassInfo {
    /// The pass's label, as [`crate::GpuTimer`] reports it.
    pub label: String,
    /// Resources read.
    pub reads: Vec<String>,
    /// Resources written (a resource read and rewritten in place is in both).
    pub writes: Vec<String>,
}

impl PassInfo {
    /// A pass labelled `label` that reads and writes nothing yet.
    pub fn new(label: impl Into<String>) -> Self {
        Self {
            label: label.into(),
            ..Self::default()
        }
    }

    /// This pass, also reading `names`.
    pub fn reads<S: Into<String>>(mut self, names: impl IntoIterator<Item = S>) -> Self {
        self.reads.extend(names.into_iter().map(Into::into));
        self
    }

    /// This pass, also writing `names`.
    pub fn writes<S: Into<String>>(mut self, names: impl IntoIterator<Item = S>) -> Self {
        self.writes.extend(names.into_iter().map(Into::into));
        self
    }

    /// This pass with every resource named `from` or `from.*` renamed to `to` / `to.*`
    /// (a shadow method declares `shadow.*`; the frame has one shadow per light).
    pub fn renamed(mut self, from: &str, to: &str) -> Self {
        let rename = |name: &mut String| {
            if name == from {
                *name = to.to_string();
            } else if let Some(rest) = name.strip_prefix(from).and_then(|r| r.strip_prefix('.')) {
                *name = format!("{to}.{rest}");
            }
        };
        self.reads.iter_mut().for_each(rename);
        self.writes.iter_mut().for_each(rename);
        self
    }
}

/// The passes of a frame in recording order, and the resources that come from outside.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FramePlan {
    inputs: Vec<String>,
    passes: Vec<PassInfo>,
}

/// A frame plan whose order is wrong.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum PlanError {
    /// A pass reads a resource no earlier pass writes and that is not an input.
    #[error(
        "pass `{pass}` reads `{resource}`, which {}",
        match .written_later_by {
            Some(later) => format!("is written only later, by `{later}`: record `{later}` first"),
            None => "no pass writes and the frame does not take as an input".to_string(),
        }
    )]
    Unwritten {
        /// The pass that reads it.
        pass: String,
        /// The resource.
        resource: String,
        /// The first later pass that writes it, if any.
        written_later_by: Option<String>,
    },
}

impl FramePlan {
    /// An empty plan whose frame takes `inputs` from outside (the mesh buffers, the
    /// targets, ...).
    pub fn new<S: Into<String>>(inputs: impl IntoIterator<Item = S>) -> Self {
        Self {
            inputs: inputs.into_iter().map(Into::into).collect(),
            passes: Vec::new(),
        }
    }

    /// Appends `passes`, recorded after those already in the plan.
    pub fn push(&mut self, passes: impl IntoIterator<Item = PassInfo>) {
        self.passes.extend(passes);
    }

    /// The passes in recording order.
    pub fn passes(&self) -> &[PassInfo] {
        &self.passes
    }

    /// The resources the frame takes from outside.
    pub fn inputs(&self) -> &[String] {
        &self.inputs
    }

    /// The labels of the passes in recording order, each once (a pass recorded once per
    /// slice of the screen appears once): what the GPU timer of a frame reports.
    pub fn labels(&self) -> Vec<&str> {
        let mut labels: Vec<&str> = Vec::new();
        for pass in &self.passes {
            if !labels.contains(&pass.label.as_str()) {
                labels.push(&pass.label);
            }
        }
        labels
    }

    /// Errors at the first pass that reads a resource neither an input nor written by an
    /// earlier pass.
    pub fn validate(&self) -> Result<(), PlanError> {
        let mut written: Vec<&str> = self.inputs.iter().map(String::as_str).collect();
        for (index, pass) in self.passes.iter().enumerate() {
            for resource in &pass.reads {
                if !written.contains(&resource.as_str()) {
                    let later = self.passes[index..]
                        .iter()
                        .find(|p| p.writes.contains(resource))
                        .map(|p| p.label.clone());
                    return Err(PlanError::Unwritten {
                        pass: pass.label.clone(),
                        resource: resource.clone(),
                        written_later_by: later,
                    });
                }
            }
            written.extend(pass.writes.iter().map(String::as_str));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_read_before_its_write_names_the_pass_to_record_first() {
        let grow = PassInfo::new("grow").reads(["mesh"]).writes(["strands"]);
        let draw = PassInfo::new("draw").reads(["strands"]).writes(["target"]);
        let mut good = FramePlan::new(["mesh"]);
        good.push([grow.clone(), draw.clone()]);
        assert_eq!(good.validate(), Ok(()));
        let mut bad = FramePlan::new(["mesh"]);
        bad.push([draw, grow]);
        let err = bad.validate().unwrap_err();
        assert_eq!(
            err,
            PlanError::Unwritten {
                pass: "draw".into(),
                resource: "strands".into(),
                written_later_by: Some("grow".into()),
            }
        );
        assert!(err.to_string().contains("record `grow` first"), "{err}");
        let mut missing = FramePlan::new(Vec::<String>::new());
        missing.push([PassInfo::new("grow").reads(["mesh"])]);
        assert!(
            missing
                .validate()
                .unwrap_err()
                .to_string()
                .contains("input")
        );
    }

    #[test]
    fn renaming_touches_the_namespace_only() {
        let p = PassInfo::new("p")
            .reads(["shadow", "shadow.grid", "shadows.x"])
            .writes(["shadow.volume"])
            .renamed("shadow", "shadow1");
        assert_eq!(p.reads, ["shadow1", "shadow1.grid", "shadows.x"]);
        assert_eq!(p.writes, ["shadow1.volume"]);
    }
}
