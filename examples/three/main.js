// stance-ik with three.js: load a glTF avatar with GLTFLoader (+ the meshopt decoder), build
// Stance's H-Anim skeleton from its skin, pull the right hand with the feet pinned and the
// centre of mass over them, and write the solved rotations into the SkinnedMesh's bones every
// frame. `window.stanceExample` exposes what the end-to-end test reads.
import * as THREE from "three";
import { GLTFLoader } from "three/addons/loaders/GLTFLoader.js";
import { MeshoptDecoder } from "three/addons/libs/meshopt_decoder.module.js";
import { Skeleton, Solver } from "stance-ik";

const params = new URLSearchParams(location.search);
const avatarUrl = params.get("avatar") ?? "../../default-avatar.glb";
const ikEnabled = params.get("ik") !== "0";
const statusLine = document.getElementById("status");
const canvas = document.getElementById("view");

const renderer = new THREE.WebGLRenderer({ canvas, antialias: true });
renderer.setPixelRatio(Math.min(devicePixelRatio, 2));
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x20232a);
scene.add(new THREE.HemisphereLight(0xffffff, 0x404050, 2.0));
const sun = new THREE.DirectionalLight(0xffffff, 2.0);
sun.position.set(1.5, 3, 2);
scene.add(sun);
scene.add(new THREE.GridHelper(4, 16, 0x5a6070, 0x3a3f4a));
const camera = new THREE.PerspectiveCamera(35, 1, 0.05, 50);
camera.position.set(0.9, 1.3, 3.4);
camera.lookAt(0, 0.95, 0);

function resize() {
  const { clientWidth: w, clientHeight: h } = canvas;
  renderer.setSize(w, h, false);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
}
addEventListener("resize", resize);
resize();

/** The avatar's skin: its bones, parents, rest world rotations and positions. */
function readSkin(root) {
  let mesh = null;
  root.traverse((o) => {
    if (!mesh && o.isSkinnedMesh) mesh = o;
  });
  if (!mesh) throw new Error(`${avatarUrl}: no skinned mesh`);
  root.updateMatrixWorld(true);
  const bones = mesh.skeleton.bones;
  const parents = bones.map((b) => bones.indexOf(b.parent));
  const rest = new Float64Array(3 * bones.length);
  const restRotation = bones.map((b, i) => {
    const p = b.getWorldPosition(new THREE.Vector3());
    rest.set([p.x, p.y, p.z], 3 * i);
    return b.getWorldQuaternion(new THREE.Quaternion());
  });
  // Parents before children, for writing world rotations down the tree.
  const depth = (b) => (b.parent && bones.includes(b.parent) ? 1 + depth(b.parent) : 0);
  const order = bones.map((_, i) => i).sort((a, b) => depth(bones[a]) - depth(bones[b]));
  return { mesh, bones, parents, rest, restRotation, order };
}

const state = { frames: 0, solveMs: [], renderMs: [], pulling: false, error: null };
window.stanceExample = state;

async function start() {
  const loader = new GLTFLoader();
  loader.setMeshoptDecoder(MeshoptDecoder);
  const gltf = await loader.loadAsync(avatarUrl);
  scene.add(gltf.scene);
  const skin = readSkin(gltf.scene);
  const skeleton = Skeleton.fromSkin(
    skin.bones.map((b) => b.name),
    Int32Array.from(skin.parents),
    skin.rest,
    2,
  );
  const names = skeleton.jointNames;
  const boneOf = skeleton.skinJoints; // skeleton joint -> bone index (-1: none)
  // Per joint, the rotation from the skin's rest onto the standard pose (qx qy qz qw).
  const restMatch = skeleton.restMatch;
  const jointOfBone = new Int32Array(skin.bones.length).fill(-1);
  boneOf.forEach((b, j) => {
    // Joints come parents first: the last one on a bone (the most distal, whose world
    // rotation includes the others') drives it.
    if (b >= 0) jointOfBone[b] = j;
  });
  // Per frame: within 8 ms, starting where the last frame ended, no restart from scratch.
  const solver = new Solver(skeleton, { max_iterations: 60, time_budget_ms: 8, restarts: false });
  const values = new Float64Array(skeleton.dofCount);
  const transforms = new Float64Array(7 * names.length);
  solver.worldTransforms(values, transforms);
  const position = (name) => {
    const j = names.indexOf(name);
    return new THREE.Vector3(transforms[7 * j], transforms[7 * j + 1], transforms[7 * j + 2]);
  };
  const feet = ["l_talocrural", "r_talocrural"].map((n) => [n, position(n)]);
  const hand = "r_radiocarpal";
  const pins = feet.map(([joint, p]) => ({ kind: "position", joint, target: p.toArray() }));
  const baseTasks = [
    ...pins,
    { kind: "balance", level: 2 },
    { kind: "posture", level: 10, weight: 0.05 },
  ];
  let handGoal = null;
  const setTasks = () =>
    solver.setTasks(
      handGoal
        ? [...baseTasks, { kind: "position", joint: hand, target: handGoal.toArray(), level: 3 }]
        : baseTasks,
    );
  setTasks();

  // Pulling: the hand follows the pointer in the plane facing the camera through the hand.
  const raycaster = new THREE.Raycaster();
  const plane = new THREE.Plane();
  const pointerGoal = (event) => {
    const rect = canvas.getBoundingClientRect();
    const ndc = new THREE.Vector2(
      ((event.clientX - rect.left) / rect.width) * 2 - 1,
      -((event.clientY - rect.top) / rect.height) * 2 + 1,
    );
    raycaster.setFromCamera(ndc, camera);
    return raycaster.ray.intersectPlane(plane, new THREE.Vector3());
  };
  canvas.addEventListener("pointerdown", (event) => {
    const normal = camera.getWorldDirection(new THREE.Vector3()).negate();
    plane.setFromNormalAndCoplanarPoint(normal, position(hand));
    state.pulling = true;
    canvas.setPointerCapture(event.pointerId);
    handGoal = pointerGoal(event) ?? position(hand);
    setTasks();
  });
  canvas.addEventListener("pointermove", (event) => {
    if (!state.pulling) return;
    const goal = pointerGoal(event);
    if (goal) {
      handGoal = goal;
      setTasks();
    }
  });
  canvas.addEventListener("pointerup", () => {
    state.pulling = false;
  });

  // The solved pose onto the bones: a mapped bone takes its joint's world rotation (from the
  // standard pose, where Stance's joint frames are parallel to the body frame) times the
  // joint's rest match times the bone's rest world rotation; the others keep their rest local
  // rotation; the root bone goes to the root joint's position.
  const rootJoint = names.indexOf("humanoid_root");
  const rootBone = boneOf[rootJoint];
  const worldRotation = skin.bones.map(() => new THREE.Quaternion());
  const parentWorld = new THREE.Quaternion();
  const jointRotation = new THREE.Quaternion();
  const matchRotation = new THREE.Quaternion();
  const restLocal = skin.bones.map((b) => b.quaternion.clone());
  function applyPose() {
    for (const i of skin.order) {
      const bone = skin.bones[i];
      const p = skin.parents[i];
      if (p >= 0) parentWorld.copy(worldRotation[p]);
      else bone.parent.getWorldQuaternion(parentWorld);
      const j = jointOfBone[i];
      if (j >= 0) {
        jointRotation.fromArray(transforms, 7 * j + 3);
        matchRotation.fromArray(restMatch, 4 * j);
        worldRotation[i].copy(jointRotation).multiply(matchRotation).multiply(skin.restRotation[i]);
        bone.quaternion.copy(parentWorld).invert().multiply(worldRotation[i]);
      } else {
        bone.quaternion.copy(restLocal[i]);
        worldRotation[i].copy(parentWorld).multiply(restLocal[i]);
      }
    }
    if (rootBone >= 0) {
      const bone = skin.bones[rootBone];
      const moved = position("humanoid_root");
      bone.parent.updateWorldMatrix(true, false);
      bone.position.copy(bone.parent.worldToLocal(moved));
    }
  }

  function frame() {
    const t0 = performance.now();
    if (ikEnabled) {
      solver.solve(values);
      solver.worldTransforms(values, transforms);
      applyPose();
    }
    const t1 = performance.now();
    renderer.render(scene, camera);
    const t2 = performance.now();
    state.frames += 1;
    state.solveMs.push(t1 - t0);
    state.renderMs.push(t2 - t1);
    if (state.solveMs.length > 600) {
      state.solveMs.shift();
      state.renderMs.shift();
    }
    const handNow = position(hand);
    state.hand = handNow.toArray();
    state.feet = feet.map(([n]) => position(n).toArray());
    state.handScreen = handNow.clone().project(camera).toArray();
    statusLine.textContent = `${names.length} H-Anim joints, ${skeleton.dofCount} DOF · IK ${(t1 - t0).toFixed(2)} ms · render ${(t2 - t1).toFixed(2)} ms`;
    requestAnimationFrame(frame);
  }
  state.joints = names.length;
  state.ready = true;
  requestAnimationFrame(frame);
}

start().catch((error) => {
  state.error = String(error);
  statusLine.textContent = `error: ${error.message ?? error}`;
  console.error(error);
});
