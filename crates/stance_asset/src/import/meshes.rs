//! Meshes: primitives with their attributes, triangle strips and fans turned into lists,
//! skinning attributes checked against their skin, and computed normals.

use glam::DVec3;
use gltf::json::{self, validation::Checked};

use super::{Ctx, bad_index};
use crate::AssetError;
use crate::model::{Mesh, Node, Primitive, Skin};

pub(super) fn import_meshes(
    ctx: &mut Ctx<'_>,
    nodes: &[Node],
    skins: &[Skin],
) -> Result<Vec<Mesh>, AssetError> {
    // Joint count of the skin each mesh is drawn with (the smallest, to check JOINTS_0).
    let mut mesh_joints: Vec<Option<usize>> = vec![None; ctx.root.meshes.len()];
    for n in nodes {
        if let (Some(m), Some(s)) = (n.mesh, n.skin)
            && let (Some(slot), Some(skin)) = (mesh_joints.get_mut(m), skins.get(s))
        {
            *slot = Some(slot.map_or(skin.joints.len(), |x: usize| x.min(skin.joints.len())));
        }
    }
    let mut meshes = Vec::new();
    let material_count = ctx.root.materials.len();
    for mi in 0..ctx.root.meshes.len() {
        let mesh = ctx.root.meshes[mi].clone();
        let mut prims = Vec::new();
        for (pi, p) in mesh.primitives.iter().enumerate() {
            let what = format!("mesh {mi} primitive {pi}");
            let mode = match p.mode {
                Checked::Valid(m) => m,
                Checked::Invalid => {
                    return Err(AssetError::BadJson(format!("{what}: invalid mode")));
                }
            };
            use json::mesh::{Mode as M, Semantic as S};
            if !matches!(mode, M::Triangles | M::TriangleStrip | M::TriangleFan) {
                ctx.warnings.push(format!(
                    "{what}: mode {mode:?} skipped (only triangles are drawn)"
                ));
                continue;
            }
            let get = |s: S| p.attributes.get(&Checked::Valid(s)).map(|a| a.value());
            let Some(pos_acc) = get(S::Positions) else {
                ctx.warnings.push(format!("{what}: no POSITION, skipped"));
                continue;
            };
            let (pos, comps) = ctx.read(pos_acc, &format!("{what} POSITION"))?;
            if comps != 3 {
                return Err(AssetError::BadAccessor(format!(
                    "{what}: POSITION must be VEC3"
                )));
            }
            let count = pos.len() / 3;
            let positions: Vec<[f32; 3]> = pos
                .chunks_exact(3)
                .map(|c| {
                    let v = [c[0], c[1], c[2]];
                    if v.iter().all(|x| x.is_finite()) {
                        v
                    } else {
                        [0.0; 3]
                    }
                })
                .collect();
            let attr = |ctx: &mut Ctx<'_>,
                        s: S,
                        name: &str,
                        want: usize|
             -> Result<Option<Vec<f32>>, AssetError> {
                let Some(a) = p.attributes.get(&Checked::Valid(s)).map(|a| a.value()) else {
                    return Ok(None);
                };
                let (v, c) = ctx.read(a, &format!("{what} {name}"))?;
                if c != want && !(name == "WEIGHTS_0" && c == 4) {
                    return Err(AssetError::BadAccessor(format!(
                        "{what}: {name} has {c} components, expected {want}"
                    )));
                }
                if v.len() / c != count {
                    return Err(AssetError::BadAccessor(format!(
                        "{what}: {name} has {} elements but POSITION has {count}",
                        v.len() / c
                    )));
                }
                Ok(Some(v))
            };
            let normals = attr(ctx, S::Normals, "NORMAL", 3)?;
            let uvs = attr(ctx, S::TexCoords(0), "TEXCOORD_0", 2)?;
            let joints = attr(ctx, S::Joints(0), "JOINTS_0", 4)?;
            let weights = attr(ctx, S::Weights(0), "WEIGHTS_0", 4)?;
            let mut indices = match p.indices {
                Some(a) => {
                    let idx = ctx.read_indices(a.value(), &format!("{what} indices"))?;
                    if let Some(&bad) = idx.iter().find(|&&i| i as usize >= count) {
                        return Err(AssetError::OutOfBounds(format!(
                            "{what}: index {bad} out of range (the primitive has {count} vertices)"
                        )));
                    }
                    idx
                }
                None => (0..count as u32).collect(),
            };
            indices = match mode {
                M::TriangleStrip => strip_to_list(&indices),
                M::TriangleFan => fan_to_list(&indices),
                _ => {
                    let whole = indices.len() - indices.len() % 3;
                    indices.truncate(whole);
                    indices
                }
            };
            // The primitive as stored (positions, normals, uvs, joints and weights per vertex,
            // u32 indices), counted before the attributes the file lacks are synthesised.
            let skinned = joints.is_some() && weights.is_some();
            let stored = count
                .saturating_mul(if skinned {
                    12 + 12 + 8 + 8 + 16
                } else {
                    12 + 12 + 8
                })
                .saturating_add(indices.len().saturating_mul(4));
            ctx.charge(stored, &what)?;
            let mut normals: Vec<[f32; 3]> = match normals {
                Some(n) => n
                    .chunks_exact(3)
                    .map(|c| unit([c[0], c[1], c[2]]))
                    .collect(),
                None => compute_normals(&positions, &indices),
            };
            normals.resize(count, [0.0, 1.0, 0.0]);
            let uvs: Vec<[f32; 2]> = match uvs {
                Some(u) => u
                    .chunks_exact(2)
                    .map(|c| {
                        let v = [c[0], c[1]];
                        if v.iter().all(|x| x.is_finite()) {
                            v
                        } else {
                            [0.0; 2]
                        }
                    })
                    .collect(),
                None => vec![[0.0; 2]; count],
            };
            let (joints, weights) = match (joints, weights) {
                (Some(j), Some(w)) => {
                    let limit = mesh_joints[mi].unwrap_or(0);
                    let mut jo = Vec::with_capacity(count);
                    let mut we = Vec::with_capacity(count);
                    for (jc, wc) in j.chunks_exact(4).zip(w.chunks_exact(4)) {
                        let mut ji = [0u16; 4];
                        let mut wi = [0f32; 4];
                        for k in 0..4 {
                            let w = if wc[k].is_finite() {
                                wc[k].max(0.0)
                            } else {
                                0.0
                            };
                            if w > 0.0 && jc[k] as usize >= limit {
                                return Err(AssetError::OutOfBounds(format!(
                                    "{what}: JOINTS_0 value {} out of range (the skin has {limit} joints)",
                                    jc[k]
                                )));
                            }
                            ji[k] = if (jc[k] as usize) < limit {
                                jc[k] as u16
                            } else {
                                0
                            };
                            wi[k] = w;
                        }
                        let sum: f32 = wi.iter().sum();
                        if sum > 1e-6 {
                            wi.iter_mut().for_each(|x| *x /= sum);
                        } else {
                            wi = [1.0, 0.0, 0.0, 0.0];
                            ji = [0; 4];
                        }
                        jo.push(ji);
                        we.push(wi);
                    }
                    if limit == 0 {
                        (Vec::new(), Vec::new())
                    } else {
                        (jo, we)
                    }
                }
                _ => (Vec::new(), Vec::new()),
            };
            let material = p.material.map(|m| m.value());
            if let Some(m) = material
                && m >= material_count
            {
                return Err(bad_index(what, "material", m, material_count));
            }
            prims.push(Primitive {
                positions,
                normals,
                uvs,
                joints,
                weights,
                indices,
                material,
            });
        }
        meshes.push(Mesh {
            name: mesh.name.clone().unwrap_or_else(|| format!("mesh{mi}")),
            primitives: prims,
        });
    }
    Ok(meshes)
}

fn unit(v: [f32; 3]) -> [f32; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if l.is_finite() && l > 1e-8 {
        [v[0] / l, v[1] / l, v[2] / l]
    } else {
        [0.0, 1.0, 0.0]
    }
}

fn strip_to_list(s: &[u32]) -> Vec<u32> {
    let mut out = Vec::new();
    for i in 2..s.len() {
        if i % 2 == 0 {
            out.extend_from_slice(&[s[i - 2], s[i - 1], s[i]]);
        } else {
            out.extend_from_slice(&[s[i - 1], s[i - 2], s[i]]);
        }
    }
    out
}

fn fan_to_list(s: &[u32]) -> Vec<u32> {
    let mut out = Vec::new();
    for i in 2..s.len() {
        out.extend_from_slice(&[s[0], s[i - 1], s[i]]);
    }
    out
}

/// Area-weighted vertex normals.
pub(crate) fn compute_normals(positions: &[[f32; 3]], indices: &[u32]) -> Vec<[f32; 3]> {
    let mut acc = vec![DVec3::ZERO; positions.len()];
    for t in indices.chunks_exact(3) {
        let p = |k: usize| {
            positions.get(t[k] as usize).map_or(DVec3::ZERO, |v| {
                DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64)
            })
        };
        let n = (p(1) - p(0)).cross(p(2) - p(0));
        for k in 0..3 {
            if let Some(a) = acc.get_mut(t[k] as usize) {
                *a += n;
            }
        }
    }
    acc.into_iter()
        .map(|n| {
            let n = n.normalize_or(DVec3::Y);
            [n.x as f32, n.y as f32, n.z as f32]
        })
        .collect()
}
