#![allow(clippy::unwrap_used)]
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let clip = stance_motion::read_bvh(&std::fs::read(&path).unwrap(), "x", &Default::default()).unwrap();
    let l = clip.joint_of("l_talocrural").unwrap();
    let r = clip.joint_of("r_talocrural").unwrap();
    let w: Vec<_> = clip.frames.iter().map(|f| clip.world(f)).collect();
    let low = w.iter().flat_map(|x| [x[l].1.y, x[r].1.y]).fold(f64::INFINITY, f64::min);
    for f in 1..w.len() - 1 {
        let s = |j: usize| { let d = w[f + 1][j].1 - w[f - 1][j].1; (d.x * d.x + d.z * d.z).sqrt() / (2.0 * clip.frame_time) };
        println!("{f:4} L h={:6.3} v={:5.2}   R h={:6.3} v={:5.2}", w[f][l].1.y - low, s(l), w[f][r].1.y - low, s(r));
    }
}
