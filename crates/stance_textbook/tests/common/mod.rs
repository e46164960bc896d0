//! Problem files of the families, as the CLI writes them.

use stance_document::problem_json;
use stance_hanim::families::{Family, families};
use stance_ik::Skeleton;
use stance_textbook::Problem;

/// `count` problems of `family` (seed 1, as `stance families` writes by default), each as
/// the oracle reads it and as Stance's problem file.
pub fn problems(family: &Family, count: usize) -> Vec<(Problem, String, Skeleton)> {
    let skeleton = family.body.skeleton().unwrap();
    (0..count)
        .map(|i| {
            let p = family.problem(&skeleton, 1, i).unwrap();
            let text = problem_json(&skeleton, &p.tasks, &p.start)
                .unwrap()
                .to_string();
            (Problem::from_json(&text).unwrap(), text, skeleton.clone())
        })
        .collect()
}

pub fn all_families() -> Vec<Family> {
    families()
}
