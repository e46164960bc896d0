#!/usr/bin/env node
// Footfall annotations for the clip corpus (crates/stance_motion/tests/clips), written apart
// from stance_motion's contact detector so that its tests have an independent oracle: its own
// BVH reader and forward kinematics (no Rust code shared), and footfalls found from the heights
// of the heel (the ankle joint) and the toe (the deepest point below the ankle) alone, with no
// speed, no smoothing and no knowledge of the detector's thresholds.
//
// A footfall of a foot is a run of frames in which both its heel and its toe are within BAND
// of their own lowest heights over the clip (5th percentile), BAND being 6 % of the clip's leg
// length (hip to knee to ankle at rest): the flat-foot core of a stance, from just after the
// heel strike to just before the heel lifts. Runs shorter than 50 ms are dropped, and two runs
// less than 50 ms apart are one footfall. Reference frames at the start (the rest pose, a
// T-pose, and the frames that blend out of it) are not annotated: the annotation starts at the
// first frame after the last one whose joint rotations are all within 3 degrees of the rest
// pose's, plus the frames over which the pose still moves faster than 200 degrees per frame
// summed over the joints (a blend or a cut out of the reference).
//
// Usage: node scripts/annotate-footfalls.mjs CLIP.bvh...   (writes CLIP.footfalls.json beside
// each clip; --print prints instead)

import { readFileSync, writeFileSync } from 'node:fs';

const BAND = 0.04;
const MIN_RUN_S = 0.05;
const MAX_GAP_S = 0.05;

function parse(text) {
  const tokens = text.split(/\s+/).filter((t) => t.length > 0);
  let i = 0;
  const joints = [];
  const stack = [];
  let channelCount = 0;
  while (i < tokens.length && tokens[i] !== 'MOTION') {
    const t = tokens[i++];
    if (t === 'ROOT' || t === 'JOINT') {
      const name = tokens[i++];
      joints.push({ name, parent: stack.length ? stack[stack.length - 1] : -1, offset: [0, 0, 0], channels: [], site: false });
    } else if (t === 'End') {
      i++; // Site
      joints.push({ name: `${joints[stack[stack.length - 1]].name}_site`, parent: stack[stack.length - 1], offset: [0, 0, 0], channels: [], site: true });
    } else if (t === '{') {
      stack.push(joints.length - 1);
    } else if (t === '}') {
      stack.pop();
    } else if (t === 'OFFSET') {
      joints[joints.length - 1].offset = [0, 1, 2].map((k) => Number(tokens[i + k]));
      i += 3;
    } else if (t === 'CHANNELS') {
      const n = Number(tokens[i++]);
      const j = joints[joints.length - 1];
      j.channels = tokens.slice(i, i + n);
      j.first = channelCount;
      channelCount += n;
      i += n;
    }
  }
  i++; // MOTION
  i++; // Frames:
  const frames = Number(tokens[i++]);
  i += 2; // Frame Time:
  const frameTime = Number(tokens[i++]);
  const values = tokens.slice(i).map(Number);
  const count = Math.min(frames, Math.floor(values.length / channelCount));
  const motion = [];
  for (let f = 0; f < count; f++) motion.push(values.slice(f * channelCount, (f + 1) * channelCount));
  return { joints, frameTime, motion };
}

const mul = (a, b) => {
  const r = new Array(9).fill(0);
  for (let x = 0; x < 3; x++) for (let y = 0; y < 3; y++) for (let k = 0; k < 3; k++) r[3 * x + y] += a[3 * x + k] * b[3 * k + y];
  return r;
};
const apply = (m, v) => [0, 1, 2].map((x) => m[3 * x] * v[0] + m[3 * x + 1] * v[1] + m[3 * x + 2] * v[2]);
function axisMatrix(axis, degrees) {
  const a = (degrees * Math.PI) / 180;
  const c = Math.cos(a);
  const s = Math.sin(a);
  if (axis === 'X') return [1, 0, 0, 0, c, -s, 0, s, c];
  if (axis === 'Y') return [c, 0, s, 0, 1, 0, -s, 0, c];
  return [c, -s, 0, s, c, 0, 0, 0, 1];
}

// World positions of every joint (and End Site) in one frame, file units and axes.
function positions(clip, row) {
  const rot = [];
  const pos = [];
  for (const [k, j] of clip.joints.entries()) {
    let local = [1, 0, 0, 0, 1, 0, 0, 0, 1];
    let t = j.offset.slice();
    for (const [c, name] of j.channels.entries()) {
      const v = row[j.first + c];
      if (name.endsWith('rotation')) local = mul(local, axisMatrix(name[0], v));
      else t['XYZ'.indexOf(name[0])] = j.parent < 0 ? v : t['XYZ'.indexOf(name[0])] + v - j.offset['XYZ'.indexOf(name[0])];
    }
    if (j.parent < 0) {
      rot[k] = local;
      pos[k] = t;
    } else {
      rot[k] = mul(rot[j.parent], local);
      const d = apply(rot[j.parent], t);
      pos[k] = [0, 1, 2].map((x) => pos[j.parent][x] + d[x]);
    }
  }
  return pos;
}

const find = (clip, patterns) => {
  for (const p of patterns) {
    const k = clip.joints.findIndex((j) => !j.site && p.test(j.name));
    if (k >= 0) return k;
  }
  return -1;
};
const side = (s) => (s === 'l' ? '(l|left|l_)' : '(r|right|r_)');
function limb(clip, s) {
  const pre = `^(character1_|mixamorig:|bip01_?)?${side(s)}`;
  const ankle = find(clip, [new RegExp(`${pre}_?(foot|ankle)$`, 'i')]);
  const knee = find(clip, [new RegExp(`${pre}_?(leg|knee|tibia|shin|calf|lowleg)$`, 'i')]);
  const hip = find(clip, [new RegExp(`${pre}_?(upleg|hip|femur|thigh|upperleg)$`, 'i')]);
  // The toe: the deepest point under the ankle (a toe joint's End Site, or the ankle's own).
  let toe = ankle;
  for (;;) {
    const child = clip.joints.findIndex((j) => j.parent === toe);
    if (child < 0) break;
    toe = child;
  }
  return { hip, knee, ankle, toe };
}

const length = (v) => Math.hypot(v[0], v[1], v[2]);
const percentile = (xs, p) => {
  const s = xs.slice().sort((a, b) => a - b);
  return s[Math.min(s.length - 1, Math.floor(p * s.length))];
};

export function annotate(text) {
  const clip = parse(text);
  const legs = { l: limb(clip, 'l'), r: limb(clip, 'r') };
  for (const [s, l] of Object.entries(legs)) {
    if (l.ankle < 0 || l.knee < 0 || l.hip < 0) throw new Error(`no ${s} leg (hip, knee, ankle) found by name`);
  }
  const leg = (l) => length(clip.joints[l.knee].offset) + length(clip.joints[l.ankle].offset);
  const legLength = (leg(legs.l) + leg(legs.r)) / 2;
  const frames = clip.motion.map((row) => positions(clip, row));
  // Up: the axis from the ankles to the head in the first frame (not at rest: some
  // exporters lay every bone along its own axis at rest).
  const head = find(clip, [/head$/i]);
  const first = frames[0];
  const up = [0, 1, 2].reduce((best, a) => {
    const h = (k) => first[head][k] - (first[legs.l.ankle][k] + first[legs.r.ankle][k]) / 2;
    return Math.abs(h(a)) > Math.abs(h(best)) ? a : best;
  }, 0);
  const upSign = Math.sign(first[head][up] - first[legs.l.ankle][up]);
  // Reference frames: at most the first two seconds, while the arms are stretched out
  // sideways (wrists at least 85 % of the skeleton's widest wrist span apart, a T-pose), then
  // the frames that blend or cut out of it (the summed joint-rotation change to the next
  // frame over three times the clip's median).
  const wrists = ['l', 'r'].map((s) => find(clip, [new RegExp(`^(character1_|mixamorig:)?${side(s)}_?(hand|wrist)$`, 'i')]));
  const rotationChannels = [];
  for (const j of clip.joints) j.channels.forEach((n, c) => n.endsWith('rotation') && j.parent >= 0 && rotationChannels.push(j.first + c));
  let start = 0;
  if (wrists.every((w) => w >= 0)) {
    // The path from one wrist to the other through their nearest common ancestor, stretched:
    // the widest span the skeleton can make.
    const ancestors = (k) => {
      const out = [];
      for (let j = k; j >= 0; j = clip.joints[j].parent) out.push(j);
      return out;
    };
    const [a, b] = wrists.map(ancestors);
    const common = a.find((j) => b.includes(j));
    const upTo = (chain) => chain.slice(0, chain.indexOf(common)).reduce((sum, j) => sum + length(clip.joints[j].offset), 0);
    const span = upTo(a) + upTo(b);
    const apart = (f) => length([0, 1, 2].map((k) => frames[f][wrists[0]][k] - frames[f][wrists[1]][k]));
    const limit = Math.min(frames.length, Math.round(2 / clip.frameTime));
    while (start < limit && apart(start) >= 0.85 * span) start++;
    if (start > 0) {
      const change = (f) => rotationChannels.reduce((sum, c) => sum + Math.abs(clip.motion[f][c] - clip.motion[f - 1][c]), 0);
      const changes = [];
      for (let f = 1; f < clip.motion.length; f++) changes.push(change(f));
      const median = percentile(changes, 0.5);
      while (start < clip.motion.length && change(start) > 3 * median) start++;
    }
  }
  const band = BAND * legLength;
  const minRun = Math.max(1, Math.round(MIN_RUN_S / clip.frameTime));
  const maxGap = Math.max(1, Math.round(MAX_GAP_S / clip.frameTime));
  const out = { frames: clip.motion.length, frame_time: clip.frameTime, start, leg_length: legLength, band, feet: {} };
  for (const [s, l] of Object.entries(legs)) {
    const h = (k) => frames.slice(start).map((p) => upSign * p[k][up]);
    const heel = h(l.ankle);
    const toe = h(l.toe);
    const heelLow = percentile(heel, 0.05);
    const toeLow = percentile(toe, 0.05);
    const down = heel.map((y, f) => Math.min(y - heelLow, toe[f] - toeLow) <= band);
    if (process.env.TRACE === s) {
      heel.forEach((y, f) => console.error(`${s} ${f + start} heel ${((y - heelLow) / band).toFixed(2)} toe ${((toe[f] - toeLow) / band).toFixed(2)} ${down[f] ? 'down' : ''}`));
    }
    let runs = [];
    for (let f = 0; f < down.length; f++) {
      if (!down[f]) continue;
      const a = f;
      while (f + 1 < down.length && down[f + 1]) f++;
      runs.push([a, f]);
    }
    const merged = [];
    for (const r of runs) {
      const last = merged[merged.length - 1];
      if (last && r[0] - last[1] - 1 < maxGap) last[1] = r[1];
      else merged.push(r.slice());
    }
    runs = merged.filter(([a, b]) => b - a + 1 >= minRun).map(([a, b]) => [a + start, b + start]);
    out.feet[s] = runs;
  }
  return out;
}

const args = process.argv.slice(2);
const print = args.includes('--print');
for (const path of args.filter((a) => a !== '--print')) {
  const result = annotate(readFileSync(path, 'utf8'));
  const text = `${JSON.stringify(result)}\n`;
  if (print) process.stdout.write(`${path}: ${text}`);
  else writeFileSync(path.replace(/\.bvh$/i, '.footfalls.json'), text);
}
