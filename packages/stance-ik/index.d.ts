// Types of the stance-ik package. The classes come from the wasm-bindgen declarations; the
// problem, task and report shapes are those of Stance's problem format.

export { Skeleton, Solver } from './pkg/stance_ik.js';

/** World axes a position or centre-of-mass task controls: "xyz", "xz", "y"... */
export type Axes = string;
/** `[x, y, z]` in metres, H-Anim frame: +Y up, +Z the body's front, +X its left. */
export type Vec3 = [number, number, number];
/** `[qx, qy, qz, qw]` (world_from_joint). */
export type Quat = [number, number, number, number];

interface TaskCommon {
  /** Priority level, 1 = highest (default 1). */
  level?: number;
  /** Weight inside the level (default 1). */
  weight?: number;
  /** Inactive tasks are kept but not solved (default true). */
  active?: boolean;
}

/** The task kinds, with the problem format's fields. */
export type Task = TaskCommon &
  (
    | { kind: 'position'; joint: string; point?: Vec3; axes?: Axes; target: Vec3 }
    | { kind: 'orientation'; joint: string; target: Quat }
    | { kind: 'direction'; joint: string; axis?: Vec3; target: Vec3 }
    | { kind: 'gaze'; joint: string; axis?: Vec3; point?: Vec3; target: Vec3 }
    | { kind: 'com'; axes?: Axes; target: Vec3 }
    | { kind: 'balance'; support?: string[]; margin?: number }
    | { kind: 'posture'; joints?: string[]; reference?: Posture }
    | {
        kind: 'limb';
        limb?: 'l_arm' | 'r_arm' | 'l_leg' | 'r_leg';
        joints?: [string, string, string];
        target: Vec3;
        swivel?: number;
        orientation?: Quat;
      }
  );

/** DOF values by joint: `{"l_knee": {"rx": 0.4}}` (radians and metres). */
export type Posture = Record<string, Partial<Record<'tx' | 'ty' | 'tz' | 'rx' | 'ry' | 'rz', number>>>;

/** One joint of a problem's skeleton. */
export interface JointDefinition {
  name: string;
  parent?: string | null;
  offset?: Vec3;
  dofs?: Array<'tx' | 'ty' | 'tz' | 'rx' | 'ry' | 'rz'>;
  limits?: Partial<Record<'tx' | 'ty' | 'tz' | 'rx' | 'ry' | 'rz', [number, number]>>;
  mass?: number;
  com?: Vec3;
}

/** Solver settings (all optional). */
export interface Settings {
  max_iterations?: number;
  tolerance?: number;
  time_budget_ms?: number;
  lambda?: number;
  adaptive_damping?: { lambda_max: number; epsilon: number };
  levels?: Record<string, { lambda?: number; adaptive_damping?: { lambda_max: number; epsilon: number } }>;
  enforce_limits?: boolean;
  hybrid?: boolean;
  [setting: string]: unknown;
}

/** A whole problem, as `stance solve` reads it. */
export interface Problem {
  skeleton: { joints: JointDefinition[] };
  tasks?: Task[];
  settings?: Settings;
  posture?: Posture;
}

/** One level of a solve. */
export interface LevelReport {
  level: number;
  tasks: number;
  rows: number;
  residual_before: number;
  residual_after: number;
  met: boolean;
  posture_only: boolean;
}

/** How a solve went. */
export interface Report {
  status: 'converged' | 'stalled' | 'iteration_budget' | 'time_budget' | string;
  iterations: number;
  levels: LevelReport[];
  /** The highest level left unmet (it gave way to the levels above). */
  gave_way: number | null;
  clamped_dofs: number;
  elapsed_secs: number | null;
  analytic_restarts: unknown[];
  /** Per task of `setTasks` (in its order), from `Solver.solve`: how it fares. */
  tasks?: TaskStatus[];
}

/** How one task of the problem fares in the solution (one per task, in the problem's order). */
export interface TaskStatus {
  level: number;
  /** The task in words, as the editor's task list writes it. */
  description: string;
  /** The norm of its error (m or rad); null when it cannot be evaluated. */
  residual: number | null;
  /** Residual within 1e-3. */
  met: boolean;
  /** Why it is not met: "conflicts with level L: TASK", "limited by joint limits" or "out of reach". */
  gave_way: string | null;
  /** Why it could not be evaluated. */
  problem: string | null;
}

/** What `solve` returns (the output of `stance solve`). */
export interface Solution {
  joints: Record<string, Vec3>;
  posture: Posture;
  report: Report;
  tasks: TaskStatus[];
  limbs?: Array<{ joints: [string, string, string]; swivel: number; start_swivel: number; reached: boolean; within_limits: boolean }>;
}

/**
 * Solves a problem (object or JSON text); throws an Error naming the offending field.
 */
export function solve(problem: Problem | string): Solution;

/** A clip retargeted onto a skeleton: one posture per source frame. */
export interface RetargetedClip {
  /** Seconds per frame (the source's). */
  frameTime: number;
  /** Frames (the source's). */
  frameCount: number;
  /** `frameCount * skeleton.dofCount` DOF values, frame after frame. */
  values: Float64Array;
  /** Contacts held (heel, ball, hands, knees, pelvis), in frames (inclusive), at `point`. */
  /** `slides`: a foot point kept on the floor while the clip moves it along, not held still. */
  contacts: {
    joint: string;
    part: string;
    start: number;
    end: number;
    slides: boolean;
    point: Vec3;
  }[];
  /** Solver iterations over the clip. */
  iterations: number;
  /** What the reader and retargeting noticed (units, unmapped joints...). */
  notes: string[];
}

/**
 * Retargets a BVH clip (text) onto an H-Anim skeleton; foot contacts held unless
 * `contacts: false`. The first call loads the retargeting module (a second WebAssembly file).
 */
export function retarget(
  skeleton: import('./pkg/stance_ik.js').Skeleton,
  bvh: string,
  options?: { contacts?: boolean },
): Promise<RetargetedClip>;
