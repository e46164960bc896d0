#!/usr/bin/env node
// Footfall annotations for the clip corpus (crates/stance_motion/tests/clips), written apart
// from stance_motion's contact detector so that its tests have an independent oracle: its own
// BVH reader and forward kinematics (no Rust code shared), and footfalls found from the heights
// of the heel (the ankle joint) and the toe (the deepest point below the ankle) alone, with no
// speed, no smoothing and no knowledge of the detector's thresholds.
//
// A footfall of a foot is a run of frames in which both its heel and its toe are within BAND
// of their own lowest heights over the clip (5th percentile), BAND being 4 % of the clip's leg
// length (knee to ankle and hip to knee at rest); precisely: the lower of the two, each less its
// own lowest, is within BAND (a foot on its heel or on its toes is down). Runs shorter than 50 ms are dropped, and two runs
// less than 50 ms apart are one footfall. Reference frames at the start (the rest pose, a
// T-pose, and the frames that blend out of it) are not annotated: the annotation starts at the
// first frame after the last one whose joint rotations are all within 3 degrees of the rest
// pose's, plus the frames over which the pose still moves faster than 200 degrees per frame
// summed over the joints (a blend or a cut out of the reference).
//
// That is one floor per clip: a foot resting on a stair or a raised step is not annotated.
// --levels annotates such clips instead (see levelsDown): footfalls at any height, from how the
// sole's height moves alone, still no speed and nothing of the detector's. --parts adds the
// knees and the hands (wrist and fingertip), one floor per clip, for clips on all fours or
// kneeling, and takes the feet by the toe alone (the ankle rests on the shin there); --up=Y
// names the file's up axis where the first frame is not upright (on all fours). All three are
// opt-in, so the annotations made without them do not change.
//
// Usage: node scripts/annotate-footfalls.mjs [--levels] [--parts] [--up=Y] CLIP.bvh...   (writes
// CLIP.footfalls.json beside each clip; --print prints instead)

import { readFileSync, writeFileSync } from 'node:fs';

const BAND = 0.04;
const MIN_RUN_S = 0.05;
const MAX_GAP_S = 0.05;
// --levels: how long either side a frame must stay still, and how far either side its level
// must be the lowest.
const STILL_S = 0.05;
const LOCAL_S = 0.2;

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
// The deepest point under a joint: follow first children to the end (a toe joint's or the
// hand's End Site, or the joint itself).
function deepest(clip, k) {
  let j = k;
  for (;;) {
    const child = clip.joints.findIndex((x) => x.parent === j);
    if (child < 0) return j;
    j = child;
  }
}
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

export function annotate(text, options = {}) {
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
  // --up=X|Y|Z (+ or -) instead: the file's own up axis, for a clip whose first frame is not
  // upright (on all fours the head is ahead of the ankles more than above them).
  const given = options.up ? /^([+-]?)([XYZ])$/i.exec(options.up) : null;
  if (options.up && !given) throw new Error(`--up=${options.up}: X, Y or Z, + or -`);
  const up = given
    ? 'XYZ'.indexOf(given[2].toUpperCase())
    : [0, 1, 2].reduce((best, a) => {
        const h = (k) => first[head][k] - (first[legs.l.ankle][k] + first[legs.r.ankle][k]) / 2;
        return Math.abs(h(a)) > Math.abs(h(best)) ? a : best;
      }, 0);
  const upSign = given ? (given[1] === '-' ? -1 : 1) : Math.sign(first[head][up] - first[legs.l.ankle][up]);
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
  if (options.levels) out.floors = 'levels';
  if (given) out.up = `${upSign < 0 ? '-' : '+'}${'XYZ'[up]}`;
  // Heights (up) of a point over the annotated frames, and their 5th percentile: the point's
  // own lowest over the clip.
  const heights = (k) => frames.slice(start).map((p) => upSign * p[k][up]);
  // A run of frames where a point pair (a joint and the deepest point below it) is down: the
  // lower of the two, each less its own lowest, is within BAND of the floor (one floor per
  // clip) or of the level it rests on (--levels).
  const annotatePair = (s, name, a, b) => {
    const ha = heights(a);
    const hb = heights(b);
    // --levels: each point's lowest itself (a foot may rest on the lowest level for a few
    // frames only), so that the two points agree on the height of every level.
    const lowA = percentile(ha, options.levels ? 0 : 0.05);
    const lowB = percentile(hb, options.levels ? 0 : 0.05);
    const d = ha.map((y, f) => Math.min(y - lowA, hb[f] - lowB));
    const down = options.levels ? levelsDown(d, [ha, hb], band, clip.frameTime) : d.map((x) => x <= band);
    if (process.env.TRACE === `${name}${s}` || (name === 'feet' && process.env.TRACE === s)) {
      ha.forEach((y, f) => console.error(`${s} ${f + start} ${name} ${((y - lowA) / band).toFixed(2)} ${((hb[f] - lowB) / band).toFixed(2)} ${down[f] ? 'down' : ''}`));
    }
    return runsOf(down, minRun, maxGap).map(([x, y]) => [x + start, y + start]);
  };
  // --parts: the feet by the toe alone. On all fours the ankle rests on the shin, never on
  // the floor, so its own lowest is no floor: a foot lying still with its toes well up would
  // count as down.
  for (const [s, l] of Object.entries(legs)) {
    out.feet[s] = annotatePair(s, 'feet', options.parts ? l.toe : l.ankle, l.toe);
  }
  if (options.parts) {
    // Knees (the knee joint alone) and hands (the wrist and the deepest point below it), each
    // with one floor per clip: for clips on all fours or kneeling, where they do reach the floor.
    out.knees = {};
    out.hands = {};
    for (const [s, l] of Object.entries(legs)) out.knees[s] = annotatePair(s, 'knees', l.knee, l.knee);
    wrists.forEach((w, i) => {
      const s = i === 0 ? 'l' : 'r';
      if (w < 0) throw new Error(`no ${s} wrist found by name`);
      out.hands[s] = annotatePair(s, 'hands', w, deepest(clip, w));
    });
  }
  return out;
}

// Runs of true frames: gaps shorter than maxGap bridged, runs shorter than minRun dropped.
function runsOf(down, minRun, maxGap) {
  const runs = [];
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
  return merged.filter(([a, b]) => b - a + 1 >= minRun);
}

// --levels: footfalls on several levels (stairs, a raised step, uneven ground), from the
// heights alone. A frame is still when the heel's or the toe's height (either: a heel strike
// or a toe-off rolls about one of them) varies by at most half the band within STILL_S either
// side; with d the sole's height (the lower of the two, each less its lowest), a run of still frames at least MIN_RUN_S long whose lowest d (its
// level) is, within half the band, the lowest of d from LOCAL_S before it to LOCAL_S after it
// (a foot resting, not the top of a swing) is grown while d stays within the band of its
// level. No speed: only how the sole's height moves.
function levelsDown(d, points, band, frameTime) {
  const k = Math.max(1, Math.round(STILL_S / frameTime));
  const w = Math.max(1, Math.round(LOCAL_S / frameTime));
  const minRun = Math.max(1, Math.round(MIN_RUN_S / frameTime));
  const n = d.length;
  const range = (a, b, h = d) => {
    let lo = Infinity;
    let hi = -Infinity;
    for (let i = Math.max(0, a); i <= Math.min(n - 1, b); i++) {
      lo = Math.min(lo, h[i]);
      hi = Math.max(hi, h[i]);
    }
    return [lo, hi];
  };
  const still = d.map((_, f) =>
    points.some((h) => {
      const [lo, hi] = range(f - k, f + k, h);
      return hi - lo <= band / 2;
    }),
  );
  const down = new Array(n).fill(false);
  for (let f = 0; f < n; f++) {
    if (!still[f]) continue;
    const a = f;
    while (f + 1 < n && still[f + 1]) f++;
    const b = f;
    if (b - a + 1 < minRun) continue;
    const level = range(a, b)[0];
    if (level > range(a - w, b + w)[0] + band / 2) continue;
    let x = a;
    while (x > 0 && d[x - 1] <= level + band) x--;
    let y = b;
    while (y < n - 1 && d[y + 1] <= level + band) y++;
    for (let i = x; i <= y; i++) down[i] = true;
  }
  return down;
}

const args = process.argv.slice(2);
const flags = new Set(args.filter((a) => a.startsWith('--') && !a.startsWith('--up=')));
for (const flag of flags) if (!['--print', '--levels', '--parts'].includes(flag)) throw new Error(`unknown option ${flag}`);
const upFlag = args.find((a) => a.startsWith('--up='));
for (const path of args.filter((a) => !a.startsWith('--'))) {
  const result = annotate(readFileSync(path, 'utf8'), { levels: flags.has('--levels'), parts: flags.has('--parts'), up: upFlag?.slice(5) });
  const text = `${JSON.stringify(result)}\n`;
  if (flags.has('--print')) process.stdout.write(`${path}: ${text}`);
  else writeFileSync(path.replace(/\.bvh$/i, '.footfalls.json'), text);
}
