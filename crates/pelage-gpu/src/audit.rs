//! What a frame actually binds, pass by pass: the check that a [`FramePlan`] is what runs.
//!
//! A plan ([`crate::FramePlan`]) lists each pass's reads and writes by resource name. This
//! module records, while an [`Audit`] is running on the thread, what the code really does:
//!
//! - every bind group layout [`crate::BindLayout::build`] creates, with its entries (so a
//!   binding's access is known: read-only storage and sampled textures are reads, writable
//!   storage and storage textures writes; uniforms are constants a stage writes in
//!   `prepare`, not frame resources, and samplers are not resources);
//! - every bind group [`crate::create_bind_group`] creates: which buffer or texture view sits
//!   at which binding of which layout;
//! - the name each resource was given with [`name_buffer`] / [`name_view`] (the plan's
//!   names: `strands.vertices`, `shadow.grid`, ...);
//! - every bind group a pass binds ([`set_bind_group`], which every stage calls instead of
//!   wgpu's `set_bind_group`), under the label of the pass being recorded (the label the
//!   pass's [`crate::GpuTimer`] scope was opened with).
//!
//! [`Audit::finish`] returns the passes with the named resources each bound and how; a
//! test compares them with the plan ([`BoundPass::undeclared`]): a pass that binds a
//! resource its declaration does not name, or a storage resource nobody named, fails.
//! Outside an audit every hook is one thread-local check.
//!
//! [`FramePlan`]: crate::FramePlan

use std::cell::RefCell;
use std::collections::{BTreeMap, HashMap};

/// How a pass uses a resource it binds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Access {
    /// Read only (read-only storage, a sampled texture).
    Read,
    /// Written, and possibly read (writable storage, a storage texture).
    Write,
}

/// A resource a bind group holds.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
enum Resource {
    Buffer(wgpu::Buffer),
    View(wgpu::TextureView),
}

/// What a bound resource is called: its name, or what it is when nobody named it.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum BoundName {
    /// Named with [`name_buffer`] or [`name_view`].
    Named(String),
    /// Data the CPU writes (at build or in `prepare`) and passes only read: like a
    /// uniform, not a frame resource ([`constant`]).
    Constant,
    /// A storage buffer or texture nobody named: the bind group's label and the binding.
    Unnamed {
        /// The bind group's label.
        group: String,
        /// The binding number.
        binding: u32,
    },
}

impl std::fmt::Display for BoundName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BoundName::Named(name) => write!(f, "`{name}`"),
            BoundName::Constant => write!(f, "a constant (CPU-written) buffer"),
            BoundName::Unnamed { group, binding } => {
                write!(f, "an unnamed resource at binding {binding} of `{group}`")
            }
        }
    }
}

/// One pass label of an audited frame: every resource its recordings bound, and how.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct BoundPass {
    /// The pass label (its GPU timer scope).
    pub label: String,
    /// Each bound resource with the strongest access any binding of it had.
    pub bound: BTreeMap<BoundName, Access>,
}

impl BoundPass {
    /// The bound resources the declaration `reads` / `writes` does not cover: a written
    /// resource must be declared written; a read one, read or written; an unnamed one is
    /// never covered. `normalise` maps a declared name to the name its resource was given
    /// (a frame's `shadow0.grid` is the shadow method's `shadow.grid`).
    pub fn undeclared(
        &self,
        reads: &[String],
        writes: &[String],
        normalise: impl Fn(&str) -> String,
    ) -> Vec<String> {
        let reads: Vec<String> = reads.iter().map(|r| normalise(r)).collect();
        let writes: Vec<String> = writes.iter().map(|w| normalise(w)).collect();
        self.bound
            .iter()
            .filter_map(|(name, access)| {
                let covered = match name {
                    BoundName::Unnamed { .. } => false,
                    BoundName::Constant => *access == Access::Read,
                    BoundName::Named(n) => match access {
                        Access::Write => writes.contains(n),
                        Access::Read => reads.contains(n) || writes.contains(n),
                    },
                };
                (!covered).then(|| {
                    let how = match access {
                        Access::Read => "reads",
                        Access::Write => "writes",
                    };
                    format!("pass `{}` {how} {name}", self.label)
                })
            })
            .collect()
    }

    /// The declared resources this pass never binds (through a bind group or as a render
    /// pass attachment): a declaration that claims more than the pass does. A declared
    /// write must be bound writable.
    pub fn unbound(
        &self,
        reads: &[String],
        writes: &[String],
        normalise: impl Fn(&str) -> String,
    ) -> Vec<String> {
        let access = |name: &str| self.bound.get(&BoundName::Named(normalise(name))).copied();
        let mut out: Vec<String> = writes
            .iter()
            .filter(|w| access(w) != Some(Access::Write))
            .map(|w| {
                format!(
                    "pass `{}` declares a write of `{w}` it does not bind writable",
                    self.label
                )
            })
            .collect();
        out.extend(
            reads
                .iter()
                .filter(|r| !writes.contains(r) && access(r).is_none())
                .map(|r| {
                    format!(
                        "pass `{}` declares a read of `{r}` it does not bind",
                        self.label
                    )
                }),
        );
        out
    }
}

#[derive(Default)]
struct State {
    layouts: HashMap<wgpu::BindGroupLayout, Vec<wgpu::BindGroupLayoutEntry>>,
    groups: HashMap<wgpu::BindGroup, Vec<(String, u32, Resource, Access)>>,
    names: HashMap<Resource, BoundName>,
    passes: Vec<BoundPass>,
}

thread_local! {
    static STATE: RefCell<Option<State>> = const { RefCell::new(None) };
}

fn with_state(f: impl FnOnce(&mut State)) {
    STATE.with(|s| {
        if let Some(state) = s.borrow_mut().as_mut() {
            f(state);
        }
    });
}

/// A running audit of this thread's GPU recording (see the module docs). Start it before
/// the stages are built (their layouts, bind groups and names are recorded as they are
/// created), record a frame, then [`Audit::finish`].
#[derive(Debug)]
#[must_use = "an audit records until it is finished or dropped"]
pub struct Audit(());

impl Audit {
    /// Starts recording on this thread (a running audit is restarted).
    pub fn start() -> Self {
        STATE.with(|s| *s.borrow_mut() = Some(State::default()));
        Audit(())
    }

    /// Forgets the passes recorded so far (the bind groups, layouts and names stay):
    /// call before the frame to audit, after the frames that build or warm up.
    pub fn clear_passes(&self) {
        with_state(|s| s.passes.clear());
    }

    /// Stops recording and returns the passes, in recording order, each label once (the
    /// bindings of a label recorded several times, per light or per slice, merged).
    pub fn finish(self) -> Vec<BoundPass> {
        let state = STATE.with(|s| s.borrow_mut().take());
        let mut merged: Vec<BoundPass> = Vec::new();
        for pass in state.map(|s| s.passes).unwrap_or_default() {
            match merged.iter_mut().find(|p| p.label == pass.label) {
                Some(p) => {
                    for (name, access) in pass.bound {
                        let a = p.bound.entry(name).or_insert(access);
                        *a = (*a).max(access);
                    }
                }
                None => merged.push(pass),
            }
        }
        merged
    }
}

impl Drop for Audit {
    fn drop(&mut self) {
        STATE.with(|s| *s.borrow_mut() = None);
    }
}

/// Names `buffer` `name` for a running audit (the plan's name of the resource it holds).
/// Outside an audit it does nothing.
pub fn name_buffer(buffer: &wgpu::Buffer, name: &str) {
    with_state(|s| {
        s.names.insert(
            Resource::Buffer(buffer.clone()),
            BoundName::Named(name.to_string()),
        );
    });
}

/// Marks `buffers` as constants for a running audit: data the CPU writes at build time
/// or in `prepare` and that passes only read (a pass binding one writable is reported).
pub fn constant(buffers: &[&wgpu::Buffer]) {
    with_state(|s| {
        for buffer in buffers {
            s.names
                .insert(Resource::Buffer((*buffer).clone()), BoundName::Constant);
        }
    });
}

/// Marks `view` as a constant for a running audit, as [`constant`] marks buffers: a
/// texture built once (outside the frame) that passes only sample.
pub fn constant_view(view: &wgpu::TextureView) {
    with_state(|s| {
        s.names
            .insert(Resource::View(view.clone()), BoundName::Constant);
    });
}

/// Names `view` `name` for a running audit, as [`name_buffer`].
pub fn name_view(view: &wgpu::TextureView, name: &str) {
    with_state(|s| {
        s.names.insert(
            Resource::View(view.clone()),
            BoundName::Named(name.to_string()),
        );
    });
}

/// Records a layout's entries (called by [`crate::BindLayout::build`]).
pub(crate) fn layout_created(
    layout: &wgpu::BindGroupLayout,
    entries: &[wgpu::BindGroupLayoutEntry],
) {
    with_state(|s| {
        s.layouts.insert(layout.clone(), entries.to_vec());
    });
}

/// The access of a binding of type `ty`, or `None` for what is not a frame resource.
fn access_of(ty: &wgpu::BindingType) -> Option<Access> {
    match ty {
        wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            ..
        } => Some(if *read_only {
            Access::Read
        } else {
            Access::Write
        }),
        wgpu::BindingType::Buffer { .. } | wgpu::BindingType::Sampler(_) => None,
        wgpu::BindingType::Texture { .. } => Some(Access::Read),
        wgpu::BindingType::StorageTexture { access, .. } => Some(match access {
            wgpu::StorageTextureAccess::ReadOnly => Access::Read,
            _ => Access::Write,
        }),
        _ => Some(Access::Read),
    }
}

/// Records a bind group's resources (called by [`crate::create_bind_group`]). A layout
/// the audit did not see being built (made before the audit started, or by wgpu's
/// automatic layouts) leaves its bind groups unrecorded: binding one is reported.
pub(crate) fn group_created(group: &wgpu::BindGroup, desc: &wgpu::BindGroupDescriptor<'_>) {
    with_state(|s| {
        let Some(entries) = s.layouts.get(desc.layout) else {
            return;
        };
        let label = desc.label.unwrap_or("unlabelled bind group").to_string();
        let mut held = Vec::new();
        for entry in desc.entries {
            let Some(access) = entries
                .iter()
                .find(|e| e.binding == entry.binding)
                .and_then(|e| access_of(&e.ty))
            else {
                continue;
            };
            let resource = match &entry.resource {
                wgpu::BindingResource::Buffer(b) => Resource::Buffer(b.buffer.clone()),
                wgpu::BindingResource::TextureView(v) => Resource::View((*v).clone()),
                _ => continue,
            };
            held.push((label.clone(), entry.binding, resource, access));
        }
        s.groups.insert(group.clone(), held);
    });
}

/// Opens the pass `label` (called when a [`crate::GpuTimer`] scope is opened): the bind
/// groups set from now on are this pass's.
pub(crate) fn pass_begun(label: &str) {
    with_state(|s| {
        s.passes.push(BoundPass {
            label: label.to_string(),
            bound: BTreeMap::new(),
        });
    });
}

fn bound(group: &wgpu::BindGroup) {
    with_state(|s| {
        // A bind group the audit did not see made (before it started, or with a layout it
        // did not see built) is reported rather than trusted: nothing passes unseen.
        let unseen = [(
            "a bind group made before the audit or with an unseen layout".to_string(),
            0,
            None,
            Access::Write,
        )];
        let resources: Vec<(BoundName, Access)> = match s.groups.get(group) {
            Some(held) => held
                .iter()
                .map(|(label, binding, resource, access)| {
                    (label.clone(), *binding, Some(resource.clone()), *access)
                })
                .collect::<Vec<_>>(),
            None => unseen.to_vec(),
        }
        .into_iter()
        .map(|(label, binding, resource, access)| {
            let name = match resource.and_then(|r| s.names.get(&r)) {
                Some(n) => n.clone(),
                None => BoundName::Unnamed {
                    group: label,
                    binding,
                },
            };
            (name, access)
        })
        .collect();
        if s.passes.is_empty() {
            s.passes.push(BoundPass {
                label: "(before any pass)".into(),
                bound: BTreeMap::new(),
            });
        }
        let Some(pass) = s.passes.last_mut() else {
            return;
        };
        for (name, access) in resources {
            let a = pass.bound.entry(name).or_insert(access);
            *a = (*a).max(access);
        }
    });
}

/// A pass a bind group can be set on (wgpu's compute and render passes).
pub trait BindGroupTarget {
    /// wgpu's `set_bind_group(index, group, &[])`.
    fn set_group(&mut self, index: u32, group: &wgpu::BindGroup);
}

impl BindGroupTarget for wgpu::ComputePass<'_> {
    fn set_group(&mut self, index: u32, group: &wgpu::BindGroup) {
        self.set_bind_group(index, group, &[]);
    }
}

impl BindGroupTarget for wgpu::RenderPass<'_> {
    fn set_group(&mut self, index: u32, group: &wgpu::BindGroup) {
        self.set_bind_group(index, group, &[]);
    }
}

impl<T: BindGroupTarget + ?Sized> BindGroupTarget for &mut T {
    fn set_group(&mut self, index: u32, group: &wgpu::BindGroup) {
        (**self).set_group(index, group);
    }
}

/// `pass.set_bind_group(index, group, &[])`, recorded by a running audit: how every stage
/// binds (a test scans the stage crates for direct calls).
pub fn set_bind_group(pass: &mut impl BindGroupTarget, index: u32, group: &wgpu::BindGroup) {
    bound(group);
    pass.set_group(index, group);
}

fn attached(view: &wgpu::TextureView, access: Access) {
    with_state(|s| {
        let name = match s.names.get(&Resource::View(view.clone())) {
            Some(n) => n.clone(),
            None => BoundName::Unnamed {
                group: "a render pass attachment".into(),
                binding: 0,
            },
        };
        if let Some(pass) = s.passes.last_mut() {
            let a = pass.bound.entry(name).or_insert(access);
            *a = (*a).max(access);
        }
    });
}

/// `encoder.begin_render_pass(desc)`, with the attachments recorded by a running audit
/// under the pass being recorded: colour and resolve targets are writes, the depth
/// attachment a write when its depth is stored and a read (a depth test) otherwise. How
/// every stage begins a render pass (a test scans the stage crates for direct calls).
pub fn begin_render_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    desc: &wgpu::RenderPassDescriptor<'_>,
) -> wgpu::RenderPass<'e> {
    for attachment in desc.color_attachments.iter().flatten() {
        attached(attachment.view, Access::Write);
        if let Some(resolve) = attachment.resolve_target {
            attached(resolve, Access::Write);
        }
    }
    if let Some(depth) = &desc.depth_stencil_attachment {
        let stored = depth
            .depth_ops
            .is_some_and(|ops| ops.store == wgpu::StoreOp::Store);
        attached(
            depth.view,
            if stored { Access::Write } else { Access::Read },
        );
    }
    encoder.begin_render_pass(desc)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pass(bound: &[(BoundName, Access)]) -> BoundPass {
        BoundPass {
            label: "p".into(),
            bound: bound.iter().cloned().collect(),
        }
    }

    fn named(n: &str) -> BoundName {
        BoundName::Named(n.into())
    }

    fn strings(names: &[&str]) -> Vec<String> {
        names.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn a_binding_must_be_declared_with_its_access() {
        let p = pass(&[
            (named("a"), Access::Read),
            (named("b"), Access::Write),
            (BoundName::Constant, Access::Read),
        ]);
        let same = |s: &str| s.to_string();
        assert!(
            p.undeclared(&strings(&["a"]), &strings(&["b"]), same)
                .is_empty()
        );
        // A read declared as a write is covered; a write declared as a read is not.
        assert!(p.undeclared(&[], &strings(&["a", "b"]), same).is_empty());
        let missing = p.undeclared(&strings(&["a", "b"]), &[], same);
        assert_eq!(missing, ["pass `p` writes `b`"]);
        // A constant bound writable, and anything unnamed, is never covered.
        let bad = pass(&[
            (BoundName::Constant, Access::Write),
            (
                BoundName::Unnamed {
                    group: "g".into(),
                    binding: 3,
                },
                Access::Read,
            ),
        ]);
        let missing = bad.undeclared(&strings(&["x"]), &strings(&["x"]), same);
        assert_eq!(missing.len(), 2, "{missing:?}");
        assert!(missing[1].contains("binding 3 of `g`"), "{missing:?}");
    }

    #[test]
    fn a_declaration_must_be_bound() {
        let p = pass(&[(named("a"), Access::Read), (named("b"), Access::Write)]);
        let same = |s: &str| s.to_string();
        assert!(
            p.unbound(&strings(&["a"]), &strings(&["b"]), same)
                .is_empty()
        );
        let extra = p.unbound(&strings(&["c"]), &strings(&["a"]), same);
        assert_eq!(
            extra,
            [
                "pass `p` declares a write of `a` it does not bind writable",
                "pass `p` declares a read of `c` it does not bind",
            ]
        );
        // The normalisation maps a frame's per-light name to the method's.
        let light = |s: &str| s.replace("shadow0", "shadow");
        let p = pass(&[(named("shadow.grid"), Access::Write)]);
        assert!(
            p.undeclared(&[], &strings(&["shadow0.grid"]), light)
                .is_empty()
        );
    }

    #[test]
    fn outside_an_audit_nothing_is_recorded() {
        pass_begun("x");
        assert!(STATE.with(|s| s.borrow().is_none()));
        let audit = Audit::start();
        pass_begun("y");
        pass_begun("y");
        pass_begun("z");
        let passes = audit.finish();
        let labels: Vec<&str> = passes.iter().map(|p| p.label.as_str()).collect();
        assert_eq!(labels, ["y", "z"]);
        assert!(STATE.with(|s| s.borrow().is_none()));
    }
}
