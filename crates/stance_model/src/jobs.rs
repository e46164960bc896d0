//! Heavy work the editor hands to its host to run off the editor's thread (the page's loading
//! worker): a clip read and retargeted ([`stance_asset::ClipJob`]), or keypoints lifted into
//! postures ([`LiftJob`]). Both go the same way ([`crate::HostHooks::run_job`]): as bytes
//! to the worker ([`HostJob::to_bytes`]), run there ([`HostJob::run_for_transfer`]), and
//! back in parts whose first names the kind ([`JobHead`]). Where the host cannot, the model
//! runs the job itself at once.

use stance_asset::{ClipJob, ClipTransfer};
use stance_document::{Document, PostureValues, Scene};
use stance_hanim::{LevelOfArticulation, SkeletonOptions, default_skeleton};
use stance_lift::{ObservedPose, flip_depth, lift_people, lifted_scene, solve};
use stance_render::OrbitCamera;

/// The first byte of a job, and of the first part of its result: which kind it is.
const CLIP: u8 = 0;
const LIFT: u8 = 1;

/// Work for the host's loading worker.
#[derive(Debug, Clone, PartialEq)]
pub enum HostJob {
    /// A clip file read and retargeted onto a body.
    Clip(Box<ClipJob>),
    /// Keypoints lifted into postures, or one lifted character's limb flipped in depth.
    Lift(Box<LiftJob>),
}

/// A job for the host, named by the request's id (the reply and progress reports carry it).
#[derive(Debug, Clone, PartialEq)]
pub struct JobRequest {
    /// Names the request.
    pub id: u64,
    /// What to do.
    pub job: HostJob,
}

/// Keypoints lifted on the mannequin at a level of articulation (what the lifted characters
/// are built on: their documents name no avatar).
#[derive(Debug, Clone, PartialEq)]
pub enum LiftJob {
    /// An OpenPose keypoints file lifted: every person in it, through the file's camera
    /// (`stance_camera`) or one fitted to the first person.
    Open {
        /// The file's name (for the messages).
        name: String,
        /// The file's text.
        keypoints: String,
        /// The body's level of articulation (1 to 4).
        loa: u8,
    },
    /// A lifted character's limb flipped in depth ([`stance_lift::flip_depth`]) and its
    /// document's tasks (each keypoint on its camera ray) solved again from there.
    Flip {
        /// The character's document (its tasks and its saved view, the keypoints' camera).
        document: Box<Document>,
        /// The body's level of articulation (1 to 4).
        loa: u8,
        /// The joint that ends the flipped segment (`r_elbow`: the right arm).
        joint: String,
    },
}

/// What came back from the worker, decoded.
#[derive(Debug, Clone, PartialEq)]
pub enum JobOutput {
    /// A clip read and retargeted.
    Clip(Box<stance_asset::OpenedClip>),
    /// The lift's result: a scene of one character per person, or (a flip) the one
    /// character's document with its new posture.
    Lift(Box<Scene>),
}

/// The first part of a job's result, by kind.
#[derive(Debug, Clone, PartialEq)]
pub enum JobHead {
    /// A clip's [`ClipTransfer`] head: its parts of frames follow.
    Clip(Vec<u8>),
    /// The whole result of a lift (a scene's JSON).
    Lift(Scene),
}

impl HostJob {
    /// Which kind it is, as the page's lanes name them (one worker each, so that a lift
    /// does not cancel a clip under way).
    pub fn kind(&self) -> &'static str {
        match self {
            HostJob::Clip(_) => "clip",
            HostJob::Lift(_) => "lift",
        }
    }

    /// The job as bytes for the trip: its kind, then the job.
    pub fn to_bytes(&self) -> Result<Vec<u8>, String> {
        let (tag, body) = match self {
            HostJob::Clip(job) => (CLIP, job.to_bytes().map_err(|e| e.to_string())?),
            HostJob::Lift(job) => (LIFT, job.to_json().into_bytes()),
        };
        let mut bytes = Vec::with_capacity(body.len() + 1);
        bytes.push(tag);
        bytes.extend_from_slice(&body);
        Ok(bytes)
    }

    /// The job again.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, String> {
        match bytes.split_first() {
            Some((&CLIP, rest)) => ClipJob::from_bytes(rest)
                .map(|job| HostJob::Clip(Box::new(job)))
                .map_err(|e| e.to_string()),
            Some((&LIFT, rest)) => LiftJob::from_json(rest).map(|job| HostJob::Lift(Box::new(job))),
            _ => Err("not a job of this editor".to_owned()),
        }
    }

    /// Runs the job (`progress`: the fraction done, where the job can tell it).
    pub fn run(self, progress: &mut dyn FnMut(f64)) -> Result<JobOutput, String> {
        match self {
            HostJob::Clip(job) => job.run(progress).map(|c| JobOutput::Clip(Box::new(c))),
            HostJob::Lift(job) => job.run().map(|s| JobOutput::Lift(Box::new(s))),
        }
    }

    /// Runs the job from its bytes (in the worker) and returns the result split for the trip
    /// back: a head naming the kind ([`JobHead::from_bytes`]), then the clip's parts of
    /// frames. `Err`: what is wrong, in the editor's words.
    pub fn run_for_transfer(
        bytes: &[u8],
        progress: &mut dyn FnMut(f64),
    ) -> Result<Vec<Vec<u8>>, String> {
        match Self::from_bytes(bytes)?.run(progress)? {
            JobOutput::Clip(opened) => {
                let transfer = ClipTransfer::new(&opened).map_err(|e| e.to_string())?;
                let mut head = vec![CLIP];
                head.extend_from_slice(&transfer.head);
                Ok(std::iter::once(head).chain(transfer.parts).collect())
            }
            JobOutput::Lift(scene) => {
                let mut head = vec![LIFT];
                head.extend_from_slice(scene.to_json(false).as_bytes());
                Ok(vec![head])
            }
        }
    }
}

impl JobHead {
    /// The head part a worker sent ([`HostJob::run_for_transfer`]).
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, String> {
        match bytes.split_first() {
            Some((&CLIP, rest)) => Ok(JobHead::Clip(rest.to_vec())),
            Some((&LIFT, rest)) => {
                let text = std::str::from_utf8(rest).map_err(|e| e.to_string())?;
                Scene::from_json(text)
                    .map(JobHead::Lift)
                    .map_err(|e| e.to_string())
            }
            _ => Err("not a result of this editor's jobs".to_owned()),
        }
    }
}

impl LiftJob {
    fn to_json(&self) -> String {
        let value = match self {
            LiftJob::Open {
                name,
                keypoints,
                loa,
            } => serde_json::json!({ "open": name, "keypoints": keypoints, "loa": loa }),
            LiftJob::Flip {
                document,
                loa,
                joint,
            } => serde_json::json!({
                "flip": joint,
                "document": Scene::of_one(document.as_ref().clone()).to_json_value(),
                "loa": loa,
            }),
        };
        value.to_string()
    }

    fn from_json(bytes: &[u8]) -> Result<Self, String> {
        let value: serde_json::Value =
            serde_json::from_slice(bytes).map_err(|e| format!("a lift job: {e}"))?;
        let text = |key: &str| value.get(key).and_then(serde_json::Value::as_str);
        let loa = value
            .get("loa")
            .and_then(serde_json::Value::as_u64)
            .and_then(|n| u8::try_from(n).ok())
            .ok_or("a lift job without its level of articulation")?;
        if let (Some(name), Some(keypoints)) = (text("open"), text("keypoints")) {
            return Ok(LiftJob::Open {
                name: name.to_owned(),
                keypoints: keypoints.to_owned(),
                loa,
            });
        }
        let joint = text("flip").ok_or("a lift job that neither opens nor flips")?;
        let scene = value
            .get("document")
            .map(Scene::from_json_value)
            .ok_or("a flip without its document")?
            .map_err(|e| e.to_string())?;
        let document = scene
            .characters
            .into_iter()
            .next()
            .ok_or("a flip without its document")?
            .document;
        Ok(LiftJob::Flip {
            document: Box::new(document),
            loa,
            joint: joint.to_owned(),
        })
    }

    /// Lifts (a scene of a character per person) or flips (a scene of the one character
    /// flipped). `Err`: what is wrong with the file or the flip, in words.
    pub fn run(&self) -> Result<Scene, String> {
        let loa = match self {
            LiftJob::Open { loa, .. } | LiftJob::Flip { loa, .. } => *loa,
        };
        let loa = LevelOfArticulation::from_number(loa)
            .ok_or_else(|| format!("no level of articulation {loa}"))?;
        let body = default_skeleton(&SkeletonOptions {
            loa,
            ..SkeletonOptions::default()
        })
        .map_err(|e| e.to_string())?;
        let skeleton = &body.skeleton;
        match self {
            LiftJob::Open { keypoints, .. } => {
                let observed =
                    ObservedPose::from_json(keypoints, None).map_err(|e| e.to_string())?;
                let people = lift_people(skeleton, &observed, None).map_err(|e| e.to_string())?;
                Ok(lifted_scene(&people))
            }
            LiftJob::Flip {
                document, joint, ..
            } => {
                let camera = document
                    .camera
                    .as_ref()
                    .map(|c| {
                        OrbitCamera::saved(c.target, c.yaw, c.pitch, c.distance, c.orthographic)
                    })
                    .ok_or("the character has no saved view: it was not lifted from keypoints")?;
                let posture = document
                    .posture
                    .to_posture_at(skeleton, "posture")
                    .map_err(|e| e.to_string())?;
                let flipped =
                    flip_depth(skeleton, &posture, &camera, joint).map_err(|e| e.to_string())?;
                let (solved, _) = solve(skeleton, document, &flipped).map_err(|e| e.to_string())?;
                // The solve can carry the limb back to its side (a flip the joints' ranges
                // cut short, comfort preferring that side): said, rather than kept as a flip
                // that changed nothing.
                let depth = depth_from_parent(skeleton, &camera, joint);
                let (before, after) = (depth(&posture), depth(&solved));
                if before * after >= 0.0 {
                    return Err(format!(
                        "the keypoints bring it back to its side ({:.0} mm behind its parent joint, then {:.0} mm): the other side does not fit them within the joints' ranges",
                        before * 1e3,
                        after * 1e3
                    ));
                }
                let mut document = document.as_ref().clone();
                document.posture = PostureValues::from_posture(skeleton, &solved);
                Ok(Scene::of_one(document))
            }
        }
    }
}

/// How much farther from `camera` the joint `joint` is than its parent joint, in a posture of
/// `skeleton` (m; 0 where the joint is unknown).
fn depth_from_parent<'a>(
    skeleton: &'a stance_ik::Skeleton,
    camera: &OrbitCamera,
    joint: &str,
) -> impl Fn(&stance_ik::Posture) -> f64 + 'a {
    let eye = camera.eye_world().as_dvec3();
    let pair = stance_hanim::resolve_joint(skeleton, joint)
        .and_then(|j| Some((j, skeleton.joints()[j].parent?)));
    move |posture| {
        let Some((j, parent)) = pair else {
            return 0.0;
        };
        let frames = stance_ik::Frames::new(skeleton, posture);
        (frames.joint_position[j] - eye).length() - (frames.joint_position[parent] - eye).length()
    }
}
