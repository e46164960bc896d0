//! The articulated body: a tree of joints with 0 to 3 rotational DOF (and optional
//! translational DOF, used by the 6-DOF root), rest offsets, per-DOF limits, masses.

use std::collections::HashMap;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::IkError;

/// One degree of freedom of a joint, about (or along) an axis of the joint's rest frame.
///
/// In the rest posture every joint frame is parallel to the world frame (H-Anim convention),
/// so `Rx` is a rotation about the parent's x axis at rest.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Dof {
    /// Translation along x of the parent frame (metres).
    Tx,
    /// Translation along y of the parent frame (metres).
    Ty,
    /// Translation along z of the parent frame (metres).
    Tz,
    /// Rotation-vector component about x (radians).
    Rx,
    /// Rotation-vector component about y (radians).
    Ry,
    /// Rotation-vector component about z (radians).
    Rz,
}

impl Dof {
    /// All six, in a fixed order.
    pub const ALL: [Dof; 6] = [Dof::Tx, Dof::Ty, Dof::Tz, Dof::Rx, Dof::Ry, Dof::Rz];

    /// Whether this is a rotational DOF.
    pub fn is_rotation(self) -> bool {
        matches!(self, Dof::Rx | Dof::Ry | Dof::Rz)
    }

    /// Axis index 0 (x), 1 (y) or 2 (z).
    pub fn axis_index(self) -> usize {
        match self {
            Dof::Tx | Dof::Rx => 0,
            Dof::Ty | Dof::Ry => 1,
            Dof::Tz | Dof::Rz => 2,
        }
    }

    /// The name used in problem files (`"rx"`...).
    pub fn name(self) -> &'static str {
        match self {
            Dof::Tx => "tx",
            Dof::Ty => "ty",
            Dof::Tz => "tz",
            Dof::Rx => "rx",
            Dof::Ry => "ry",
            Dof::Rz => "rz",
        }
    }

    /// Parses `"tx"`..`"rz"`.
    pub fn from_name(name: &str) -> Option<Dof> {
        Dof::ALL.into_iter().find(|d| d.name() == name)
    }
}

/// Description of one joint, as given by a user or a file.
#[derive(Debug, Clone, PartialEq)]
pub struct JointDef {
    /// Unique name (H-Anim names for humanoids).
    pub name: String,
    /// Parent joint name; `None` for the root.
    pub parent: Option<String>,
    /// Rest position relative to the parent joint (parent frame, metres). For the root: its
    /// rest position in the world.
    pub offset: DVec3,
    /// The joint's degrees of freedom (any order, each at most once).
    pub dofs: Vec<Dof>,
    /// Optional limits `(dof, lower, upper)`; radians for rotations, metres for translations.
    pub limits: Vec<(Dof, f64, f64)>,
    /// Mass of the segment carried by this joint (kg); 0 if unknown.
    pub mass: f64,
    /// Centre of mass of that segment in the joint frame (relative to the joint centre, m).
    pub com: DVec3,
    /// Optional stiffness `(dof, s)` of rotation DOF, H-Anim's `stiffness`: 0 (default) moves
    /// freely, toward 1 the DOF resists motion (the solver weighs it by `1 / (1 - s)`).
    pub stiffness: Vec<(Dof, f64)>,
}

impl JointDef {
    /// A joint with the given DOF, no limits and no mass.
    pub fn new(name: impl Into<String>, parent: Option<&str>, offset: DVec3, dofs: &[Dof]) -> Self {
        Self {
            name: name.into(),
            parent: parent.map(str::to_owned),
            offset,
            dofs: dofs.to_vec(),
            limits: Vec::new(),
            mass: 0.0,
            com: DVec3::ZERO,
            stiffness: Vec::new(),
        }
    }

    /// Sets a DOF's stiffness (builder style).
    pub fn with_stiffness(mut self, dof: Dof, stiffness: f64) -> Self {
        self.stiffness.retain(|(d, _)| *d != dof);
        self.stiffness.push((dof, stiffness));
        self
    }

    /// Adds a limit (builder style).
    pub fn with_limit(mut self, dof: Dof, lower: f64, upper: f64) -> Self {
        self.limits.push((dof, lower, upper));
        self
    }

    /// Sets mass and centre of mass (builder style).
    pub fn with_mass(mut self, mass: f64, com: DVec3) -> Self {
        self.mass = mass;
        self.com = com;
        self
    }
}

/// A validated joint of a [`Skeleton`].
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    /// Unique name.
    pub name: String,
    /// Index of the parent joint (always smaller than this joint's index); `None` for the root.
    pub parent: Option<usize>,
    /// Rest offset from the parent joint, parent frame (m).
    pub offset: DVec3,
    /// Index of the first DOF of this joint in a [`crate::Posture`].
    pub dof_start: usize,
    /// The joint's DOF, in posture order (`dof_start..dof_start + dofs.len()`).
    pub dofs: Vec<Dof>,
    /// Segment mass (kg).
    pub mass: f64,
    /// Segment centre of mass in the joint frame (m).
    pub com: DVec3,
    /// Posture index of the rx/ry/rz DOF, when present.
    pub rotation_dof: [Option<usize>; 3],
    /// Posture index of the tx/ty/tz DOF, when present.
    pub translation_dof: [Option<usize>; 3],
}

impl Joint {
    /// Number of DOF of this joint.
    pub fn dof_count(&self) -> usize {
        self.dofs.len()
    }

    /// Posture indices of this joint's DOF.
    pub fn dof_range(&self) -> std::ops::Range<usize> {
        self.dof_start..self.dof_start + self.dofs.len()
    }

    /// True when the joint has at least one rotational DOF.
    pub fn has_rotation(&self) -> bool {
        self.rotation_dof.iter().any(Option::is_some)
    }
}

/// A tree of joints in topological order (every parent before its children).
#[derive(Debug, Clone, PartialEq)]
pub struct Skeleton {
    joints: Vec<Joint>,
    by_name: HashMap<String, usize>,
    dof_joint: Vec<usize>,
    dof_kind: Vec<Dof>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    stiffness: Vec<f64>,
    total_mass: f64,
}

/// A stiffness is a number in [0, 1).
fn valid_stiffness(value: f64) -> bool {
    (0.0..1.0).contains(&value)
}

impl Skeleton {
    /// Validates the joint list and builds the skeleton. Joints may come in any order; they
    /// are stored parents-first (depth first, children in the given order).
    ///
    /// Rejects duplicate names, unknown parents, cycles, zero or several roots, repeated DOF,
    /// bad limits, non-finite numbers and negative masses.
    pub fn new(defs: Vec<JointDef>) -> Result<Self, IkError> {
        if defs.is_empty() {
            return Err(IkError::Empty);
        }
        let mut index_of: HashMap<&str, usize> = HashMap::new();
        for (i, d) in defs.iter().enumerate() {
            if index_of.insert(d.name.as_str(), i).is_some() {
                return Err(IkError::DuplicateJoint(d.name.clone()));
            }
        }
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); defs.len()];
        let mut roots = Vec::new();
        for (i, d) in defs.iter().enumerate() {
            check_finite_vec(d.offset, || format!("joint `{}` offset", d.name))?;
            check_finite_vec(d.com, || format!("joint `{}` com", d.name))?;
            if !d.mass.is_finite() {
                return Err(IkError::NotFinite {
                    what: format!("joint `{}` mass", d.name),
                });
            }
            if d.mass < 0.0 {
                return Err(IkError::NegativeMass(d.name.clone()));
            }
            match &d.parent {
                None => roots.push(i),
                Some(p) => match index_of.get(p.as_str()) {
                    Some(&pi) => children[pi].push(i),
                    None => {
                        return Err(IkError::UnknownParent {
                            joint: d.name.clone(),
                            parent: p.clone(),
                        });
                    }
                },
            }
        }
        if roots.len() != 1 {
            // With no root at all, every joint sits on a cycle or hangs below one.
            if roots.is_empty() {
                return Err(IkError::Cycle(defs[0].name.clone()));
            }
            return Err(IkError::RootCount(roots.len()));
        }
        // Depth-first order from the root.
        let mut order = Vec::with_capacity(defs.len());
        let mut stack = vec![roots[0]];
        while let Some(i) = stack.pop() {
            order.push(i);
            for &c in children[i].iter().rev() {
                stack.push(c);
            }
        }
        if order.len() != defs.len() {
            let mut seen = vec![false; defs.len()];
            for &i in &order {
                seen[i] = true;
            }
            let culprit = seen.iter().position(|s| !s).unwrap_or(0);
            return Err(IkError::Cycle(defs[culprit].name.clone()));
        }
        let mut new_index = vec![0usize; defs.len()];
        for (new, &old) in order.iter().enumerate() {
            new_index[old] = new;
        }

        let mut joints = Vec::with_capacity(defs.len());
        let mut by_name = HashMap::new();
        let mut dof_joint = Vec::new();
        let mut dof_kind = Vec::new();
        let mut lower = Vec::new();
        let mut upper = Vec::new();
        let mut stiffness = Vec::new();
        let mut total_mass = 0.0;
        for (new, &old) in order.iter().enumerate() {
            let d = &defs[old];
            let parent = d
                .parent
                .as_deref()
                .and_then(|p| index_of.get(p))
                .map(|&pi| new_index[pi]);
            let dof_start = dof_kind.len();
            let mut rotation_dof = [None; 3];
            let mut translation_dof = [None; 3];
            for (k, &dof) in d.dofs.iter().enumerate() {
                let slot = if dof.is_rotation() {
                    &mut rotation_dof[dof.axis_index()]
                } else {
                    &mut translation_dof[dof.axis_index()]
                };
                if slot.is_some() {
                    return Err(IkError::DuplicateDof {
                        joint: d.name.clone(),
                        dof: dof.name().to_owned(),
                    });
                }
                *slot = Some(dof_start + k);
                dof_joint.push(new);
                dof_kind.push(dof);
                lower.push(f64::NEG_INFINITY);
                upper.push(f64::INFINITY);
            }
            for &(dof, lo, hi) in &d.limits {
                let Some(k) = d.dofs.iter().position(|&x| x == dof) else {
                    return Err(IkError::LimitWithoutDof {
                        joint: d.name.clone(),
                        dof: dof.name().to_owned(),
                    });
                };
                if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
                    return Err(IkError::BadLimit {
                        joint: d.name.clone(),
                        dof: dof.name().to_owned(),
                    });
                }
                lower[dof_start + k] = lo;
                upper[dof_start + k] = hi;
            }
            stiffness.resize(dof_kind.len(), 0.0);
            for &(dof, value) in &d.stiffness {
                let Some(k) = d.dofs.iter().position(|&x| x == dof) else {
                    return Err(IkError::BadStiffness {
                        joint: d.name.clone(),
                        dof: dof.name().to_owned(),
                    });
                };
                if !dof.is_rotation() || !valid_stiffness(value) {
                    return Err(IkError::BadStiffness {
                        joint: d.name.clone(),
                        dof: dof.name().to_owned(),
                    });
                }
                stiffness[dof_start + k] = value;
            }
            total_mass += d.mass;
            by_name.insert(d.name.clone(), new);
            joints.push(Joint {
                name: d.name.clone(),
                parent,
                offset: d.offset,
                dof_start,
                dofs: d.dofs.clone(),
                mass: d.mass,
                com: d.com,
                rotation_dof,
                translation_dof,
            });
        }
        Ok(Self {
            joints,
            by_name,
            dof_joint,
            dof_kind,
            lower,
            upper,
            stiffness,
            total_mass,
        })
    }

    /// The joint list that builds this skeleton again with [`Skeleton::new`] (parents
    /// first; limits where a DOF has them, stiffness where it is not 0): to hand a skeleton
    /// to another thread as plain data.
    pub fn joint_defs(&self) -> Vec<JointDef> {
        self.joints
            .iter()
            .map(|joint| {
                let range = joint.dof_range();
                let limits = joint
                    .dofs
                    .iter()
                    .zip(range.clone())
                    .filter(|&(_, d)| self.lower[d].is_finite() && self.upper[d].is_finite())
                    .map(|(&dof, d)| (dof, self.lower[d], self.upper[d]))
                    .collect();
                let stiffness = joint
                    .dofs
                    .iter()
                    .zip(range)
                    .filter(|&(_, d)| self.stiffness[d] != 0.0)
                    .map(|(&dof, d)| (dof, self.stiffness[d]))
                    .collect();
                JointDef {
                    name: joint.name.clone(),
                    parent: joint
                        .parent
                        .and_then(|p| self.joints.get(p))
                        .map(|p| p.name.clone()),
                    offset: joint.offset,
                    dofs: joint.dofs.clone(),
                    limits,
                    mass: joint.mass,
                    com: joint.com,
                    stiffness,
                }
            })
            .collect()
    }

    /// Per DOF: its stiffness in [0, 1) (H-Anim's `stiffness`; 0 for translations).
    pub fn stiffness(&self) -> &[f64] {
        &self.stiffness
    }

    /// Sets the stiffness of rotation DOF `dof` (in [0, 1)).
    pub fn set_stiffness(&mut self, dof: usize, value: f64) -> Result<(), IkError> {
        let rotation = self.dof_kind.get(dof).is_some_and(|k| k.is_rotation());
        if !rotation || !valid_stiffness(value) {
            let joint = self
                .dof_joint
                .get(dof)
                .and_then(|&j| self.joints.get(j))
                .map_or_else(|| format!("DOF {dof}"), |j| j.name.clone());
            return Err(IkError::BadStiffness {
                joint,
                dof: self.dof_kind.get(dof).map_or("?", |k| k.name()).to_owned(),
            });
        }
        self.stiffness[dof] = value;
        Ok(())
    }

    /// The joints, parents first.
    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }

    /// Number of joints.
    pub fn joint_count(&self) -> usize {
        self.joints.len()
    }

    /// Total number of DOF (N).
    pub fn dof_count(&self) -> usize {
        self.dof_kind.len()
    }

    /// Index of a joint by name.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.by_name.get(name).copied()
    }

    /// Index of a joint by name, as a `Result`.
    pub fn require_joint(&self, name: &str) -> Result<usize, IkError> {
        self.joint_index(name)
            .ok_or_else(|| IkError::UnknownJoint(name.to_owned()))
    }

    /// The joint that owns a DOF.
    pub fn dof_joint(&self, dof: usize) -> usize {
        self.dof_joint[dof]
    }

    /// The kind of each DOF.
    pub fn dof_kinds(&self) -> &[Dof] {
        &self.dof_kind
    }

    /// Lower limits per DOF (`-inf` when free).
    pub fn lower_limits(&self) -> &[f64] {
        &self.lower
    }

    /// Upper limits per DOF (`+inf` when free).
    pub fn upper_limits(&self) -> &[f64] {
        &self.upper
    }

    /// Sum of the segment masses (kg).
    pub fn total_mass(&self) -> f64 {
        self.total_mass
    }

    /// Human-readable DOF name, `joint.rx`.
    pub fn dof_name(&self, dof: usize) -> String {
        let j = &self.joints[self.dof_joint[dof]];
        format!("{}.{}", j.name, self.dof_kind[dof].name())
    }

    /// Posture indices of the DOF of `joint` and all its ancestors (the only non-zero
    /// Jacobian columns of a point on that joint's segment), root first.
    pub fn chain_dofs(&self, joint: usize) -> Vec<usize> {
        let mut chain = Vec::new();
        let mut j = Some(joint);
        while let Some(i) = j {
            let jt = &self.joints[i];
            for d in jt.dof_range().rev() {
                chain.push(d);
            }
            j = jt.parent;
        }
        chain.reverse();
        chain
    }

    /// The joints of the body rooted at `root`: `root` and everything below it, a range
    /// (joints are stored depth first). Empty when `root` is out of range.
    pub fn body_joints(&self, root: usize) -> std::ops::Range<usize> {
        if root >= self.joints.len() {
            return 0..0;
        }
        let end = (root + 1..self.joints.len())
            .find(|&j| !self.is_ancestor_or_self(root, j))
            .unwrap_or(self.joints.len());
        root..end
    }

    /// The mass of the body rooted at `root` (kg); the whole skeleton's for joint 0.
    pub fn body_mass(&self, root: usize) -> f64 {
        self.joints
            .get(self.body_joints(root))
            .map_or(0.0, |joints| joints.iter().map(|j| j.mass).sum())
    }

    /// Posture indices of the DOF that move the body rooted at `root`: those of its joints and
    /// of the joints above it, in posture order.
    pub fn body_dofs(&self, root: usize) -> Vec<usize> {
        let joints = self.body_joints(root);
        let mut dofs = match self.joints.get(root).and_then(|j| j.parent) {
            Some(parent) => self.chain_dofs(parent),
            None => Vec::new(),
        };
        if let (Some(first), Some(last)) = (
            self.joints.get(joints.start),
            joints.end.checked_sub(1).and_then(|l| self.joints.get(l)),
        ) {
            dofs.extend(first.dof_start..last.dof_start + last.dof_count());
        }
        dofs
    }

    /// Whether `ancestor` is `joint` or one of its ancestors.
    pub fn is_ancestor_or_self(&self, ancestor: usize, joint: usize) -> bool {
        let mut j = Some(joint);
        while let Some(i) = j {
            if i == ancestor {
                return true;
            }
            if i < ancestor {
                return false;
            }
            j = self.joints[i].parent;
        }
        false
    }
}

fn check_finite_vec(v: DVec3, what: impl FnOnce() -> String) -> Result<(), IkError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(IkError::NotFinite { what: what() })
    }
}
