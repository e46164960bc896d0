//! The bundled default avatar: an H-Anim-named LOA2 humanoid at the H-Anim default joint
//! centres, with a skinned mesh of capsules and ellipsoids (smooth weights across each
//! joint), generated deterministically (`stance make-avatar`).

use glam::{DMat4, DQuat, DVec3};
use stance_hanim::{LevelOfArticulation, Mapping, humanoid_joints};

use crate::AssetError;
use crate::import::compute_normals;
use crate::model::{AlphaMode, Avatar, Material, Mesh, Node, Primitive, Skin, SourceFormat, Trs};

const SKIN: usize = 0;
const CLOTH: usize = 1;

/// One body part: a capsule from `a` to `b` (points), radii at each end, squash factors of
/// the radial x and z (world), carried by `joint`, blending toward its parent near `a` and
/// toward `distal` near `b`.
struct Part {
    joint: &'static str,
    distal: Option<&'static str>,
    a: DVec3,
    b: DVec3,
    ra: f64,
    rb: f64,
    squash: DVec3,
    material: usize,
}

fn smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Generates the default avatar.
pub fn make_default_avatar() -> Result<Avatar, AssetError> {
    let joints = humanoid_joints(LevelOfArticulation::Loa2);
    let centre = |name: &str| -> Result<DVec3, AssetError> {
        joints
            .iter()
            .find(|j| j.definition.name == name)
            .map(|j| j.rest_centre)
            .ok_or_else(|| AssetError::Export(format!("no H-Anim joint {name}")))
    };
    let parent_of = |name: &str| -> Option<&'static str> {
        let j = joints.iter().find(|j| j.definition.name == name)?;
        j.parent.map(|p| joints[p].definition.name)
    };
    // Nodes: the 71 LOA2 joints, then the mesh node.
    let mut nodes: Vec<Node> = joints
        .iter()
        .map(|j| {
            let parent_centre = j.parent.map_or(DVec3::ZERO, |p| joints[p].rest_centre);
            let rest = Trs {
                translation: j.rest_centre - parent_centre,
                ..Trs::default()
            };
            Node {
                name: j.definition.name.to_owned(),
                parent: j.parent,
                children: Vec::new(),
                rest,
                pose: rest,
                mesh: None,
                skin: None,
            }
        })
        .collect();
    for i in 0..nodes.len() {
        if let Some(p) = nodes[i].parent {
            nodes[p].children.push(i);
        }
    }
    let body_node = nodes.len();
    nodes.push(Node {
        name: "body".into(),
        parent: None,
        children: Vec::new(),
        rest: Trs::default(),
        pose: Trs::default(),
        mesh: Some(0),
        skin: Some(0),
    });
    let skin = Skin {
        name: "body".into(),
        joints: (0..joints.len()).collect(),
        inverse_bind_matrices: joints
            .iter()
            .map(|j| DMat4::from_translation(-j.rest_centre).as_mat4())
            .collect(),
    };

    let mut parts = Vec::new();
    let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let round = DVec3::ONE;
    let trunk = v(1.45, 1.0, 0.85);
    let front = v(0.0, 0.0, 0.075);
    // Trunk along the spine (the vertebral centres lie near the back).
    let spine = ["vl5", "vl3", "vl1", "vt10", "vt6", "vt1"];
    let radii = [0.105, 0.1, 0.1, 0.105, 0.11, 0.09];
    parts.push(Part {
        joint: "sacroiliac",
        distal: None,
        a: centre("l_hip")? * v(0.75, 1.0, 1.0) + v(0.0, 0.0, 0.005),
        b: centre("r_hip")? * v(0.75, 1.0, 1.0) + v(0.0, 0.0, 0.005),
        ra: 0.09,
        rb: 0.09,
        squash: v(1.0, 0.8, 0.95),
        material: CLOTH,
    });
    parts.push(Part {
        joint: "humanoid_root",
        distal: Some("vl5"),
        a: centre("humanoid_root")? + v(0.0, 0.02, -0.01),
        b: centre("vl5")? + front,
        ra: 0.11,
        rb: 0.105,
        squash: trunk,
        material: CLOTH,
    });
    for k in 0..spine.len() - 1 {
        parts.push(Part {
            joint: spine[k],
            distal: Some(spine[k + 1]),
            a: centre(spine[k])? + front,
            b: centre(spine[k + 1])? + front * if k + 1 == spine.len() - 1 { 0.6 } else { 1.0 },
            ra: radii[k],
            rb: radii[k + 1],
            squash: trunk,
            material: CLOTH,
        });
    }
    // Neck and head.
    parts.push(Part {
        joint: "vc4",
        distal: Some("skullbase"),
        a: centre("vt1")? + v(0.0, 0.02, 0.02),
        b: centre("skullbase")?,
        ra: 0.052,
        rb: 0.048,
        squash: round,
        material: SKIN,
    });
    let head = centre("skullbase")? + v(0.0, 0.085, 0.025);
    parts.push(Part {
        joint: "skullbase",
        distal: None,
        a: head - v(0.0, 0.03, 0.0),
        b: head + v(0.0, 0.03, 0.0),
        ra: 0.085,
        rb: 0.085,
        squash: v(0.9, 1.0, 1.1),
        material: SKIN,
    });
    for side in ["l_", "r_"] {
        let n = |s: &str| -> &'static str {
            joints
                .iter()
                .map(|j| j.definition.name)
                .find(|name| *name == format!("{side}{s}"))
                .unwrap_or("")
        };
        let c = |s: &str| centre(&format!("{side}{s}"));
        let sx = if side == "l_" { 1.0 } else { -1.0 };
        // Shoulder girdle and arm.
        parts.push(Part {
            joint: n("sternoclavicular"),
            distal: Some(n("acromioclavicular")),
            a: c("sternoclavicular")? - v(sx * 0.03, 0.0, -0.02),
            b: c("acromioclavicular")?,
            ra: 0.045,
            rb: 0.05,
            squash: round,
            material: CLOTH,
        });
        parts.push(Part {
            joint: n("acromioclavicular"),
            distal: Some(n("shoulder")),
            a: c("acromioclavicular")?,
            b: c("shoulder")?,
            ra: 0.05,
            rb: 0.05,
            squash: round,
            material: CLOTH,
        });
        parts.push(Part {
            joint: n("shoulder"),
            distal: Some(n("elbow")),
            a: c("shoulder")?,
            b: c("elbow")?,
            ra: 0.047,
            rb: 0.037,
            squash: round,
            material: CLOTH,
        });
        parts.push(Part {
            joint: n("elbow"),
            distal: Some(n("radiocarpal")),
            a: c("elbow")?,
            b: c("radiocarpal")?,
            ra: 0.036,
            rb: 0.027,
            squash: round,
            material: SKIN,
        });
        parts.push(Part {
            joint: n("radiocarpal"),
            distal: None,
            a: c("radiocarpal")?,
            b: c("metacarpophalangeal_3")?,
            ra: 0.028,
            rb: 0.032,
            squash: v(0.45, 1.0, 1.0),
            material: SKIN,
        });
        // Fingers: metacarpophalangeal -> proximal -> distal interphalangeal -> tip.
        for f in 2..=5 {
            let chain = [
                format!("metacarpophalangeal_{f}"),
                format!("carpal_proximal_interphalangeal_{f}"),
                format!("carpal_distal_interphalangeal_{f}"),
            ];
            let p: Vec<DVec3> = chain.iter().map(|s| c(s)).collect::<Result<_, _>>()?;
            let tip = p[2] + (p[2] - p[1]) * 0.8;
            let ends = [p[0], p[1], p[2], tip];
            for k in 0..3 {
                parts.push(Part {
                    joint: n(&chain[k]),
                    distal: chain.get(k + 1).map(|s| n(s)),
                    a: ends[k],
                    b: ends[k + 1],
                    ra: 0.0095,
                    rb: 0.0085,
                    squash: round,
                    material: SKIN,
                });
            }
        }
        let thumb = [
            "carpometacarpal_1",
            "metacarpophalangeal_1",
            "carpal_interphalangeal_1",
        ];
        let p: Vec<DVec3> = thumb.iter().map(|s| c(s)).collect::<Result<_, _>>()?;
        let tip = p[2] + (p[2] - p[1]) * 0.9;
        let ends = [p[0], p[1], p[2], tip];
        for k in 0..3 {
            parts.push(Part {
                joint: n(thumb[k]),
                distal: thumb.get(k + 1).map(|s| n(s)),
                a: ends[k],
                b: ends[k + 1],
                ra: 0.012,
                rb: 0.01,
                squash: round,
                material: SKIN,
            });
        }
        // Leg and foot.
        parts.push(Part {
            joint: n("hip"),
            distal: Some(n("knee")),
            a: c("hip")? + v(0.0, 0.02, 0.01),
            b: c("knee")?,
            ra: 0.08,
            rb: 0.052,
            squash: round,
            material: CLOTH,
        });
        parts.push(Part {
            joint: n("knee"),
            distal: Some(n("talocrural")),
            a: c("knee")?,
            b: c("talocrural")?,
            ra: 0.05,
            rb: 0.034,
            squash: round,
            material: CLOTH,
        });
        let ankle = c("talocrural")?;
        let toe = c("metatarsophalangeal_2")?;
        parts.push(Part {
            joint: n("talocrural"),
            distal: Some(n("metatarsophalangeal_2")),
            a: v(ankle.x, 0.035, ankle.z - 0.03),
            b: v(toe.x, 0.03, toe.z),
            ra: 0.035,
            rb: 0.03,
            squash: v(1.2, 1.0, 1.0),
            material: SKIN,
        });
        let tip = c("tarsal_distal_interphalangeal_2")?;
        parts.push(Part {
            joint: n("metatarsophalangeal_2"),
            distal: None,
            a: v(toe.x, 0.025, toe.z),
            b: v(tip.x, 0.022, tip.z + 0.02),
            ra: 0.026,
            rb: 0.021,
            squash: v(1.3, 1.0, 1.0),
            material: SKIN,
        });
    }

    let index_of = |name: &str| joints.iter().position(|j| j.definition.name == name);
    let mut prims = vec![Primitive::default(), Primitive::default()];
    for (m, p) in prims.iter_mut().enumerate() {
        p.material = Some(m);
    }
    for part in &parts {
        let Some(j) = index_of(part.joint) else {
            return Err(AssetError::Export(format!(
                "part on unknown joint {}",
                part.joint
            )));
        };
        let parent = parent_of(part.joint).and_then(index_of);
        let distal = part.distal.and_then(index_of);
        add_capsule(&mut prims[part.material], part, j, parent, distal);
    }
    for p in &mut prims {
        p.normals = compute_normals(&p.positions, &p.indices);
    }
    let materials = vec![
        Material {
            name: "skin".into(),
            base_color_factor: [0.78, 0.6, 0.49, 1.0],
            alpha_mode: AlphaMode::Opaque,
            ..Material::default()
        },
        Material {
            name: "clothes".into(),
            base_color_factor: [0.22, 0.3, 0.42, 1.0],
            ..Material::default()
        },
    ];
    let mut avatar = Avatar {
        format: SourceFormat::Generated,
        nodes,
        scene_roots: vec![0, body_node],
        skins: vec![skin],
        meshes: vec![Mesh {
            name: "body".into(),
            primitives: prims,
        }],
        materials,
        textures: Vec::new(),
        hanim_from_file: DMat4::IDENTITY,
        mapping: Mapping::empty(0),
        animations: Vec::new(),
        extensions: Vec::new(),
        vrm: None,
        warnings: Vec::new(),
    };
    avatar.mapping = Mapping::auto(&avatar.source_joints(), &[], false);
    Ok(avatar)
}

fn add_capsule(
    p: &mut Primitive,
    part: &Part,
    joint: usize,
    parent: Option<usize>,
    distal: Option<usize>,
) {
    const AROUND: usize = 16;
    const RINGS: usize = 14;
    let axis = part.b - part.a;
    let len = axis.length().max(1e-6);
    let dir = axis / len;
    let rot = DQuat::from_rotation_arc(DVec3::Y, dir);
    let centre_line = |t: f64| part.a + axis * t;
    let base = p.positions.len() as u32;
    // Rings: hemisphere at a (RINGS/2 rings from the pole), cylinder, hemisphere at b.
    let half = RINGS / 2;
    let mut rows: Vec<(f64, f64, f64)> = Vec::new(); // (t along axis incl. caps, radius scale, r)
    for k in 0..=half {
        let phi = std::f64::consts::FRAC_PI_2 * k as f64 / half as f64; // 0 at pole
        let r = part.ra * phi.sin();
        let t = -part.ra * phi.cos() / len;
        rows.push((t, r, 0.0));
    }
    for k in (0..=half).rev() {
        let phi = std::f64::consts::FRAC_PI_2 * k as f64 / half as f64;
        let r = part.rb * phi.sin();
        let t = 1.0 + part.rb * phi.cos() / len;
        rows.push((t, r, 0.0));
    }
    let row_count = rows.len();
    for (ri, &(t, r, _)) in rows.iter().enumerate() {
        let ring_count = if ri == 0 || ri == row_count - 1 {
            1
        } else {
            AROUND
        };
        for k in 0..ring_count {
            let theta = std::f64::consts::TAU * k as f64 / AROUND as f64;
            let radial = rot * DVec3::new(theta.cos() * r, 0.0, theta.sin() * r);
            let pos = centre_line(t) + radial * part.squash;
            p.positions.push([pos.x as f32, pos.y as f32, pos.z as f32]);
            p.uvs.push([
                k as f32 / AROUND as f32,
                (ri as f32) / (row_count - 1) as f32,
            ]);
            // Weights along the segment.
            let tc = t.clamp(0.0, 1.0);
            let to_parent = if parent.is_some() {
                0.5 * (1.0 - smoothstep(0.0, 0.3, tc))
            } else {
                0.0
            };
            let to_distal = if distal.is_some() {
                0.5 * smoothstep(0.7, 1.0, tc)
            } else {
                0.0
            };
            let own = 1.0 - to_parent - to_distal;
            let mut js = [joint as u16, 0, 0, 0];
            let mut ws = [own as f32, 0.0, 0.0, 0.0];
            let mut slot = 1;
            if let Some(pa) = parent
                && to_parent > 0.0
            {
                js[slot] = pa as u16;
                ws[slot] = to_parent as f32;
                slot += 1;
            }
            if let Some(d) = distal
                && to_distal > 0.0
            {
                js[slot] = d as u16;
                ws[slot] = to_distal as f32;
            }
            p.joints.push(js);
            p.weights.push(ws);
        }
    }
    // Triangles.
    let ring_start = |ri: usize| -> u32 {
        if ri == 0 {
            base
        } else {
            base + 1 + ((ri - 1) * AROUND) as u32
        }
    };
    for ri in 0..row_count - 1 {
        let a0 = ring_start(ri);
        let b0 = ring_start(ri + 1);
        for k in 0..AROUND as u32 {
            let k1 = (k + 1) % AROUND as u32;
            if ri == 0 {
                p.indices.extend_from_slice(&[a0, b0 + k, b0 + k1]);
            } else if ri + 1 == row_count - 1 {
                p.indices.extend_from_slice(&[a0 + k, b0, a0 + k1]);
            } else {
                p.indices
                    .extend_from_slice(&[a0 + k, b0 + k1, a0 + k1, a0 + k, b0 + k, b0 + k1]);
            }
        }
    }
}
