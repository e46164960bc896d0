//! Prop meshes ([`stance_asset::load_prop_mesh`]): a GLB built here with known triangles and
//! node transforms against hand-computed numbers, the Khronos sample `Box.gltf` against its
//! published accessor bounds, and the named errors.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use glam::DVec3;
use serde_json::{Value, json};
use stance_asset::{AssetError, MAX_PROP_VERTICES, PropMesh, load_prop_mesh};

use crate::common;

fn load(bytes: &[u8]) -> Result<PropMesh, AssetError> {
    load_prop_mesh(bytes, &mut |_| None)
}

/// A GLB of one triangle mesh (`positions`, corners `[0, 1, 2]`, no normals, a bluish
/// material) drawn by the nodes given, the scene's roots `roots`.
fn triangle_glb(positions: &[[f32; 3]], nodes: Value, roots: Value) -> Vec<u8> {
    let mut bin: Vec<u8> = positions
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let indices_at = bin.len();
    for i in [0u16, 1, 2, 0] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let json = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": roots}],
        "nodes": nodes,
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.4, 0.6, 1.0]}}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": positions.len(), "type": "VEC3"},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": indices_at},
            {"buffer": 0, "byteOffset": indices_at, "byteLength": 6}
        ],
        "buffers": [{"byteLength": bin.len()}]
    });
    common::join(&json, &bin)
}

const TRIANGLE: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

fn near(a: [f32; 3], b: [f64; 3]) -> bool {
    a.iter()
        .zip(b)
        .all(|(x, y)| (f64::from(*x) - y).abs() < 1e-6)
}

/// Node 1 (under node 0: moved to (1, 2, 3), scaled 2) turns the triangle a quarter about +Y;
/// node 2 mirrors it in X and moves it to z = -5; node 3 draws it outside the scene.
#[test]
fn node_transforms_are_baked_by_hand() {
    let half = std::f32::consts::FRAC_1_SQRT_2;
    let nodes = json!([
        {"translation": [1, 2, 3], "scale": [2, 2, 2], "children": [1]},
        {"rotation": [0, half, 0, half], "mesh": 0},
        {"translation": [0, 0, -5], "scale": [-1, 1, 1], "mesh": 0},
        {"translation": [100, 0, 0], "mesh": 0}
    ]);
    let mesh = load(&triangle_glb(&TRIANGLE, nodes, json!([0, 2]))).unwrap();
    assert_eq!(mesh.parts.len(), 2, "node 3 is not in the scene");
    assert_eq!((mesh.vertex_count(), mesh.triangle_count()), (6, 2));
    // A quarter turn about +Y takes x to -z and y stays: (1,0,0) -> (0,0,-1); then x2, +(1,2,3).
    let turned = &mesh.parts[0];
    for (got, want) in
        turned
            .positions
            .iter()
            .zip([[1.0, 2.0, 3.0], [1.0, 2.0, 1.0], [1.0, 4.0, 3.0]])
    {
        assert!(near(*got, want), "{got:?} {want:?}");
    }
    // No normals in the file: computed, the face's +Z turned to +X.
    for n in &turned.normals {
        assert!(near(*n, [1.0, 0.0, 0.0]), "{n:?}");
    }
    assert_eq!(turned.indices, [0, 1, 2]);
    assert_eq!(turned.color_linear, [0.2, 0.4, 0.6, 1.0]);
    // Mirrored: the points at x -> -x, z - 5; the triangle turned over so that it still faces
    // its normal (+Z: a mirror in X leaves +Z as it is).
    let mirrored = &mesh.parts[1];
    for (got, want) in
        mirrored
            .positions
            .iter()
            .zip([[0.0, 0.0, -5.0], [-1.0, 0.0, -5.0], [0.0, 1.0, -5.0]])
    {
        assert!(near(*got, want), "{got:?} {want:?}");
    }
    assert_eq!(mirrored.indices, [0, 2, 1]);
    for n in &mirrored.normals {
        assert!(near(*n, [0.0, 0.0, 1.0]), "{n:?}");
    }
    // The box over both: x -1..1, y 0..4, z -5..3.
    assert!(
        (mesh.min - DVec3::new(-1.0, 0.0, -5.0)).length() < 1e-6,
        "{}",
        mesh.min
    );
    assert!(
        (mesh.max - DVec3::new(1.0, 4.0, 3.0)).length() < 1e-6,
        "{}",
        mesh.max
    );
    // Fitted into a 1 m cube: centred on (0, 2, -1), scaled (1/2, 1/4, 1/8); (1, 4, 3) is the
    // corner (0.5, 0.5, 0.5).
    let fitted = mesh.fitted([1.0, 1.0, 1.0]);
    assert!(near(fitted[0].positions[2], [0.5, 0.5, 0.5]));
    assert!(near(fitted[1].positions[0], [0.0, -0.5, -0.5]));
}

/// Khronos glTF-Sample-Models `2.0/Box` (CC BY 4.0, Cesium; tests/fixtures/LICENSE-Box.md): a
/// unit cube whose POSITION accessor is published as min (-0.5, -0.5, -0.5), max (0.5, 0.5,
/// 0.5), 24 vertices and 36 indices, red (base colour 0.8, 0, 0), under a root node turning
/// -90 degrees about X (file +Z up to glTF's +Y up).
#[test]
fn the_khronos_box_is_a_red_unit_cube() {
    let mesh = load(include_bytes!("fixtures/Box.gltf")).unwrap();
    assert_eq!((mesh.vertex_count(), mesh.triangle_count()), (24, 12));
    assert!(
        (mesh.min - DVec3::splat(-0.5)).length() < 1e-6,
        "{}",
        mesh.min
    );
    assert!(
        (mesh.max - DVec3::splat(0.5)).length() < 1e-6,
        "{}",
        mesh.max
    );
    let part = &mesh.parts[0];
    assert!((part.color_linear[0] - 0.8).abs() < 1e-6);
    // The first vertex (-0.5, -0.5, 0.5) with normal (0, 0, 1) in the file: the root's matrix
    // takes y to -z and z to y.
    assert!(
        near(part.positions[0], [-0.5, 0.5, 0.5]),
        "{:?}",
        part.positions[0]
    );
    assert!(
        near(part.normals[0], [0.0, 1.0, 0.0]),
        "{:?}",
        part.normals[0]
    );
    // Every normal points out of the cube, and every triangle faces its normal.
    for (p, n) in part.positions.iter().zip(&part.normals) {
        let outward = DVec3::from(p.map(f64::from)).dot(DVec3::from(n.map(f64::from)));
        assert!((outward - 0.5).abs() < 1e-6, "{p:?} {n:?}");
    }
    for t in part.indices.chunks_exact(3) {
        let p = |k: usize| DVec3::from(part.positions[t[k] as usize].map(f64::from));
        let face = (p(1) - p(0)).cross(p(2) - p(0));
        let n = DVec3::from(part.normals[t[0] as usize].map(f64::from));
        assert!(face.dot(n) > 0.0, "{t:?}");
    }
}

#[test]
fn errors_are_named() {
    let not = load(b"hello").unwrap_err();
    assert!(matches!(not, AssetError::NotGltf(_)), "{not}");
    // The only node drawing the mesh is outside the scene.
    let nodes = json!([{"name": "empty"}, {"mesh": 0}]);
    let none = load(&triangle_glb(&TRIANGLE, nodes, json!([0]))).unwrap_err();
    assert_eq!(none, AssetError::NoTriangles);
    assert!(none.to_string().contains("no triangles"), "{none}");
    let many = vec![[0.0f32, 0.0, 0.0]; MAX_PROP_VERTICES + 1];
    let big = load(&triangle_glb(&many, json!([{"mesh": 0}]), json!([0]))).unwrap_err();
    assert!(
        matches!(big, AssetError::TooLarge { size, limit, .. }
            if size == MAX_PROP_VERTICES as u64 + 1 && limit == MAX_PROP_VERTICES as u64),
        "{big}"
    );
    // A cut file: an error, no panic.
    let whole = triangle_glb(&TRIANGLE, json!([{"mesh": 0}]), json!([0]));
    assert!(load(&whole[..whole.len() - 20]).is_err());
}
