//! The accessibility bridge against egui itself: the tree it publishes names egui's widgets
//! with ARIA roles, and the actions the page sends reach them.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
use std::sync::{Arc, Mutex};

use stance_web::accessibility::{AccessibilityBridge, AxNode, AxTree, PageAction, PendingActions};

struct Fixture {
    ctx: egui::Context,
    published: Arc<Mutex<Vec<AxTree>>>,
    pending: PendingActions,
    weight: f64,
    active: bool,
    clicks: usize,
    /// Seconds of the next frame (each frame 0.2 s after the last unless set).
    time: f64,
}

impl Fixture {
    fn new() -> Self {
        let ctx = egui::Context::default();
        let published = Arc::new(Mutex::new(Vec::new()));
        let pending = PendingActions::default();
        let sink = Arc::clone(&published);
        ctx.add_plugin(AccessibilityBridge::new(
            Box::new(move |tree, json| {
                assert!(json.contains(&tree.root));
                sink.lock().unwrap().push(tree.clone());
            }),
            pending.clone(),
        ));
        Self {
            ctx,
            published,
            pending,
            weight: 1.0,
            active: true,
            clicks: 0,
            time: 0.0,
        }
    }

    /// One frame of a small tasks panel.
    fn frame(&mut self) {
        let input = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(
                egui::Pos2::ZERO,
                egui::vec2(800.0, 600.0),
            )),
            time: Some(self.time),
            ..Default::default()
        };
        self.time += 0.2;
        let (weight, active, clicks) = (&mut self.weight, &mut self.active, &mut self.clicks);
        let mut output = self.ctx.run_ui(input, |ui| {
            if ui.button("Add task").clicked() {
                *clicks += 1;
            }
            let label = ui.label("weight");
            ui.add(egui::DragValue::new(weight).range(0.0..=100.0).speed(0.5))
                .labelled_by(label.id);
            ui.checkbox(active, "active");
        });
        output.textures_delta.clear();
    }

    fn last(&self) -> AxTree {
        self.published.lock().unwrap().last().cloned().unwrap()
    }

    fn node(&self, role: &str, name: &str) -> AxNode {
        let tree = self.last();
        let named = |n: &AxNode| {
            n.name.as_deref() == Some(name)
                || n.labelled_by.iter().any(|l| {
                    tree.nodes
                        .iter()
                        .any(|m| &m.id == l && m.name.as_deref() == Some(name))
                })
        };
        tree.nodes
            .iter()
            .find(|n| n.role == role && named(n))
            .cloned()
            .unwrap_or_else(|| panic!("no {role} named {name:?} in {:#?}", tree.nodes))
    }
}

#[test]
fn widgets_are_published_with_roles_names_values_and_places() {
    let mut f = Fixture::new();
    f.frame();
    let button = f.node("button", "Add task");
    assert!(button.focusable);
    let [x, y, w, h] = button.bounds.unwrap();
    assert!(
        x >= 0.0 && y >= 0.0 && w > 10.0 && h > 5.0,
        "{:?}",
        button.bounds
    );
    let weight = f.node("spinbutton", "weight");
    assert_eq!(weight.numeric, Some([Some(1.0), Some(0.0), Some(100.0)]));
    let active = f.node("checkbox", "active");
    assert_eq!(active.checked, Some(true));
    // Every node is reachable from the root, in reading order: the button before the field.
    let tree = f.last();
    let order: Vec<&str> = reading_order(&tree);
    assert_eq!(
        order.len(),
        tree.nodes.len(),
        "every node hangs from the root once"
    );
    let at = |id: &str| order.iter().position(|o| *o == id).unwrap();
    assert!(at(&button.id) < at(&weight.id) && at(&weight.id) < at(&active.id));
}

fn reading_order(tree: &AxTree) -> Vec<&str> {
    let mut out = Vec::new();
    let mut stack = vec![tree.root.as_str()];
    while let Some(id) = stack.pop() {
        out.push(id);
        if let Some(node) = tree.nodes.iter().find(|n| n.id == id) {
            stack.extend(node.children.iter().rev().map(String::as_str));
        }
    }
    out
}

#[test]
fn page_actions_operate_the_widgets() {
    let mut f = Fixture::new();
    f.frame();
    let button = f.node("button", "Add task").id;
    assert!(f.pending.push(&button, PageAction::Click));
    f.frame();
    assert_eq!(f.clicks, 1, "a click from the page presses the button");

    let weight = f.node("spinbutton", "weight").id;
    assert!(f.pending.push(&weight, PageAction::SetNumber(2.5)));
    f.frame();
    assert_eq!(f.weight, 2.5);
    assert!(f.pending.push(&weight, PageAction::Increment));
    f.frame();
    assert_eq!(f.weight, 3.0, "one step is the field's speed");
    f.frame();
    assert_eq!(
        f.node("spinbutton", "weight").numeric.unwrap()[0],
        Some(3.0),
        "the published value follows"
    );

    let active = f.node("checkbox", "active").id;
    assert!(f.pending.push(&active, PageAction::Click));
    f.frame();
    assert!(!f.active);
    f.frame();
    assert_eq!(f.node("checkbox", "active").checked, Some(false));

    assert!(f.pending.push(&button, PageAction::Focus));
    f.frame();
    f.frame();
    assert_eq!(
        f.last().focus,
        button,
        "focus from the page moves egui's focus"
    );
}

#[test]
fn an_unchanged_tree_is_published_once() {
    let mut f = Fixture::new();
    f.frame();
    f.frame();
    f.frame();
    let count = f.published.lock().unwrap().len();
    assert_eq!(count, 1);
    f.weight = 7.0;
    f.frame();
    assert_eq!(f.published.lock().unwrap().len(), 2);
}

#[test]
fn changes_are_published_at_most_ten_times_a_second_and_none_is_lost() {
    let mut f = Fixture::new();
    f.frame();
    let start = f.time;
    // Frames 20 ms apart, the value changing every frame (as during a drag).
    for i in 0..10 {
        f.time = start + 0.02 * f64::from(i);
        f.weight = f64::from(i);
        f.frame();
    }
    let during = f.published.lock().unwrap().len();
    assert!(during <= 3, "{during} trees in 0.2 s");
    // The last change is held back, then published by a later frame.
    f.time = start + 0.5;
    f.frame();
    assert_eq!(
        f.node("spinbutton", "weight").numeric.unwrap()[0],
        Some(9.0)
    );
}

#[test]
fn bad_actions_from_the_page_are_refused() {
    assert_eq!(PageAction::parse("set_number", Some("abc")), None);
    assert_eq!(PageAction::parse("set_number", Some("NaN")), None);
    assert_eq!(PageAction::parse("set_number", None), None);
    assert_eq!(PageAction::parse("set_text", None), None);
    assert_eq!(PageAction::parse("explode", None), None);
    assert_eq!(
        PageAction::parse("set_number", Some(" 4.5 ")),
        Some(PageAction::SetNumber(4.5))
    );
    assert_eq!(
        PageAction::parse("set_text", Some("hi")),
        Some(PageAction::SetText("hi".into()))
    );
    assert!(!PendingActions::default().push("not a number", PageAction::Click));
}
