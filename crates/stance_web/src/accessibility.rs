//! Screen readers and keyboards in the browser: egui describes its widgets to AccessKit, but
//! eframe's web runner drops that description (only its native runners have an AccessKit
//! adapter). [`AccessibilityBridge`] is an egui plugin that takes the tree egui builds every
//! frame, turns it into a plain description of nodes with ARIA roles and names ([`AxTree`],
//! JSON) for `web/accessibility.js` to mirror as DOM elements over the canvas, and feeds the
//! actions those elements receive (click, focus, a new value, a step up or down) back to egui
//! as AccessKit action requests, which its widgets already answer.

use std::sync::{Arc, Mutex, PoisonError};

use egui::accesskit::{self, Action, ActionData, ActionRequest, NodeId, Role, Toggled, TreeId};
use serde::Serialize;

/// One widget or container, as the page mirrors it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AxNode {
    /// egui's node id, as a decimal string (ids are 64-bit hashes: JSON numbers would round
    /// them).
    pub id: String,
    /// The ARIA role (`button`, `checkbox`, `spinbutton`, ...); `generic` for containers and
    /// `text` for labels.
    pub role: &'static str,
    /// The accessible name, when the node has its own.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Ids of the nodes whose text names this one (a field named by the label beside it).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub labelled_by: Vec<String>,
    /// The value as text (a text field's content, a drag value as shown).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub value: Option<String>,
    /// Hover text.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// `[value, min, max]` of a number field or slider (`null` where unbounded).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub numeric: Option<[Option<f64>; 3]>,
    /// A checkbox's or toggle's state.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub checked: Option<bool>,
    /// An open or closed combo box or collapsing header.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub expanded: Option<bool>,
    /// A selected choice.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub selected: Option<bool>,
    /// Shown but not operable.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub disabled: bool,
    /// Takes keyboard focus.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub focusable: bool,
    /// `[x, y, width, height]` in CSS pixels from the canvas' top left corner.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bounds: Option<[f64; 4]>,
    /// Child node ids, in reading order.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub children: Vec<String>,
}

/// The whole tree of one frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AxTree {
    /// The root node's id.
    pub root: String,
    /// The node egui's keyboard focus is on (the root when none).
    pub focus: String,
    /// Every node (in no particular order: `children` gives the reading order).
    pub nodes: Vec<AxNode>,
}

/// The ARIA role that speaks for an AccessKit role in the page.
pub fn aria_role(role: Role) -> &'static str {
    match role {
        // A collapsing header opens and closes with a press (`expanded` says which).
        Role::Button | Role::DefaultButton | Role::DisclosureTriangle | Role::ColorWell => "button",
        Role::CheckBox => "checkbox",
        Role::Switch => "switch",
        Role::RadioButton => "radio",
        Role::TextInput
        | Role::MultilineTextInput
        | Role::SearchInput
        | Role::EmailInput
        | Role::NumberInput
        | Role::PasswordInput
        | Role::PhoneNumberInput
        | Role::UrlInput => "textbox",
        Role::SpinButton => "spinbutton",
        Role::Slider => "slider",
        Role::ComboBox | Role::EditableComboBox => "combobox",
        Role::MenuBar => "menubar",
        Role::Menu => "menu",
        Role::MenuItem => "menuitem",
        Role::MenuItemCheckBox => "menuitemcheckbox",
        Role::MenuItemRadio => "menuitemradio",
        Role::Tab => "tab",
        Role::TabList => "tablist",
        Role::TabPanel => "tabpanel",
        Role::Link => "link",
        Role::Image => "img",
        Role::ProgressIndicator => "progressbar",
        Role::Heading => "heading",
        Role::Tooltip => "tooltip",
        Role::ListBox => "listbox",
        Role::ListBoxOption => "option",
        Role::List => "list",
        Role::ListItem => "listitem",
        Role::Window | Role::Dialog => "group",
        Role::Label => "text",
        _ => "generic",
    }
}

fn id(node: NodeId) -> String {
    node.0.to_string()
}

/// The page's description of an AccessKit tree update (egui sends the whole tree every frame).
pub fn describe(update: &accesskit::TreeUpdate) -> AxTree {
    let root = update.tree.as_ref().map_or_else(
        || {
            update
                .nodes
                .first()
                .map(|(n, _)| id(*n))
                .unwrap_or_default()
        },
        |tree| id(tree.root),
    );
    // egui's root scales points to physical pixels; the page positions in CSS pixels, which
    // are points.
    let nodes = update
        .nodes
        .iter()
        .map(|(node_id, node)| {
            let role = node.role();
            let bounds = node
                .bounds()
                .filter(|_| node.transform().is_none())
                .map(|r| [r.x0, r.y0, r.x1 - r.x0, r.y1 - r.y0]);
            let numeric = node.numeric_value().map(|value| {
                [
                    Some(value),
                    node.min_numeric_value(),
                    node.max_numeric_value(),
                ]
            });
            // Static text carries its words as its value (AccessKit's convention): they are
            // its name in the page.
            let text = role == Role::Label;
            let name = node.label().or(node.value().filter(|_| text));
            AxNode {
                id: id(*node_id),
                role: aria_role(role),
                name: name.map(str::to_owned).filter(|l| !l.is_empty()),
                labelled_by: node.labelled_by().iter().copied().map(id).collect(),
                value: node.value().filter(|_| !text).map(str::to_owned),
                description: node.description().map(str::to_owned),
                numeric,
                checked: node.toggled().map(|t| t == Toggled::True),
                expanded: node.is_expanded(),
                selected: node.is_selected(),
                disabled: node.is_disabled(),
                focusable: node.supports_action(Action::Focus),
                bounds,
                children: node.children().iter().copied().map(id).collect(),
            }
        })
        .collect();
    AxTree {
        root,
        focus: id(update.focus),
        nodes,
    }
}

/// What a page element asks of its widget.
#[derive(Debug, Clone, PartialEq)]
pub enum PageAction {
    /// Pressed (a click, Enter or Space).
    Click,
    /// Took keyboard focus.
    Focus,
    /// One step up (arrow key on a number field or slider).
    Increment,
    /// One step down.
    Decrement,
    /// A new number typed into a number field or set on a slider.
    SetNumber(f64),
    /// New text typed into a text field.
    SetText(String),
}

impl PageAction {
    /// Reads the page's words for an action (`click`, `focus`, `increment`, `decrement`,
    /// `set_number` and `set_text` with the value as text); `None` for anything else or a
    /// number that does not parse.
    pub fn parse(action: &str, value: Option<&str>) -> Option<Self> {
        Some(match action {
            "click" => Self::Click,
            "focus" => Self::Focus,
            "increment" => Self::Increment,
            "decrement" => Self::Decrement,
            "set_number" => {
                let number: f64 = value?.trim().parse().ok()?;
                Self::SetNumber(number.is_finite().then_some(number)?)
            }
            "set_text" => Self::SetText(value?.to_owned()),
            _ => return None,
        })
    }

    fn request(self, target: u64) -> ActionRequest {
        let (action, data) = match self {
            Self::Click => (Action::Click, None),
            Self::Focus => (Action::Focus, None),
            Self::Increment => (Action::Increment, None),
            Self::Decrement => (Action::Decrement, None),
            Self::SetNumber(v) => (Action::SetValue, Some(ActionData::NumericValue(v))),
            Self::SetText(text) => (Action::SetValue, Some(ActionData::Value(text.into()))),
        };
        ActionRequest {
            action,
            target_tree: TreeId::ROOT,
            target_node: NodeId(target),
            data,
        }
    }
}

/// Actions from the page, waiting for the next frame's input.
#[derive(Debug, Clone, Default)]
pub struct PendingActions(Arc<Mutex<Vec<ActionRequest>>>);

impl PendingActions {
    /// Queues `action` for the widget with node id `target` (as [`AxNode::id`] writes it);
    /// false when the id does not parse.
    pub fn push(&self, target: &str, action: PageAction) -> bool {
        let Ok(target) = target.parse::<u64>() else {
            return false;
        };
        self.0
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .push(action.request(target));
        true
    }

    fn drain(&self) -> Vec<ActionRequest> {
        std::mem::take(&mut *self.0.lock().unwrap_or_else(PoisonError::into_inner))
    }
}

/// Where the bridge sends a changed tree (the page, or a test).
pub type Publish = Box<dyn FnMut(&AxTree, &str) + Send + Sync>;

/// The shortest time between two published trees (s): a screen reader does not need every
/// frame of a pull, and the page need not rebuild its mirror 60 times a second.
pub const PUBLISH_INTERVAL: f64 = 0.1;

/// The egui plugin (see the module's documentation). Publishes the tree as JSON when it
/// changed, at most every [`PUBLISH_INTERVAL`] (at once when the keyboard focus moved); a
/// change held back is published by a repaint it asks for.
pub struct AccessibilityBridge {
    publish: Publish,
    pending: PendingActions,
    last: String,
    last_focus: Option<NodeId>,
    last_time: f64,
}

impl AccessibilityBridge {
    /// A bridge that publishes to `publish` and takes actions from `pending`.
    pub fn new(publish: Publish, pending: PendingActions) -> Self {
        Self {
            publish,
            pending,
            last: String::new(),
            last_focus: None,
            last_time: f64::NEG_INFINITY,
        }
    }
}

impl egui::Plugin for AccessibilityBridge {
    fn debug_name(&self) -> &'static str {
        "stance_accessibility"
    }

    fn setup(&mut self, ctx: &egui::Context) {
        ctx.enable_accesskit();
    }

    fn input_hook(&mut self, _ctx: &egui::Context, input: &mut egui::RawInput) {
        input.events.extend(
            self.pending
                .drain()
                .into_iter()
                .map(egui::Event::AccessKitActionRequest),
        );
    }

    fn output_hook(&mut self, ctx: &egui::Context, output: &mut egui::FullOutput) {
        let Some(update) = &output.platform_output.accesskit_update else {
            return;
        };
        let now = ctx.input(|i| i.time);
        let wait = self.last_time + PUBLISH_INTERVAL - now;
        if wait > 0.0 && self.last_focus == Some(update.focus) {
            // Looked at again when the interval is over (egui repaints then).
            ctx.request_repaint_after(std::time::Duration::from_secs_f64(wait));
            return;
        }
        let tree = describe(update);
        let Ok(json) = serde_json::to_string(&tree) else {
            return;
        };
        if json != self.last {
            (self.publish)(&tree, &json);
            self.last = json;
            self.last_time = now;
        }
        self.last_focus = Some(update.focus);
    }
}
