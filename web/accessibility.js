// The editor's widgets for screen readers and keyboards. egui draws every widget on the canvas
// and describes them to AccessKit; eframe's web runner drops that description, so the editor
// publishes it (crates/stance_web/src/accessibility.rs: nodes with ARIA roles, names, values,
// places, children) and this module mirrors it as real DOM elements laid over the canvas:
// transparent and deaf to the mouse, but in the browser's accessibility tree and in the Tab
// order, with a visible focus ring. What the elements receive (a press, focus, a step, a typed
// value) goes back to egui as AccessKit actions, which its widgets answer as they would a
// native screen reader's.

const PRESSABLE = new Set([
  "button", "checkbox", "switch", "radio", "combobox", "menuitem", "menuitemcheckbox",
  "menuitemradio", "tab", "link", "option",
]);
const RANGED = new Set(["spinbutton", "slider"]);
const CONTAINER_ROLES = new Set([
  "group", "menubar", "menu", "tablist", "tabpanel", "listbox", "list", "listitem", "tooltip",
  "heading", "img", "progressbar",
]);

// `act(id, action, value)` sends an action to the editor (`WebHandle.accessibility_action`).
export function createAccessibilityMirror(canvas, act) {
  const root = document.createElement("div");
  root.id = "a11y";
  root.setAttribute("role", "region");
  root.setAttribute("aria-label", "Stance editor");
  canvas.after(root);
  const elements = new Map();
  const kinds = new Map();
  let lastFocus = null;
  // Tab on the canvas moves egui's focus from widget to widget; the page's focus then follows
  // it into the mirror (so that a screen reader announces the widget, and the next keys reach
  // it). A click on the canvas (e.g. into a text field) leaves the page's focus where it is.
  let tabbedOnCanvas = false;
  canvas.addEventListener("keydown", (event) => {
    if (event.key === "Tab") tabbedOnCanvas = true;
  }, true);
  canvas.addEventListener("pointerdown", () => { tabbedOnCanvas = false; }, true);

  function kindOf(node) {
    if (PRESSABLE.has(node.role)) return "button";
    if (RANGED.has(node.role)) return "range";
    if (node.role === "textbox") return "text";
    if (node.role === "text") return "label";
    return "container";
  }

  function create(node, kind) {
    let element;
    if (kind === "button") {
      element = document.createElement("button");
      element.type = "button";
      element.addEventListener("click", () => act(element.dataset.node, "click"));
    } else if (kind === "range" || kind === "text") {
      element = document.createElement("input");
      element.type = "text";
      if (kind === "range") {
        element.inputMode = "decimal";
        element.addEventListener("keydown", (event) => {
          const step = { ArrowUp: "increment", ArrowRight: "increment",
            ArrowDown: "decrement", ArrowLeft: "decrement" }[event.key];
          if (!step) return;
          event.preventDefault();
          act(element.dataset.node, step);
        });
      }
      element.addEventListener("change", () => act(element.dataset.node,
        kind === "range" ? "set_number" : "set_text", element.value));
    } else if (kind === "label") {
      element = document.createElement("span");
    } else {
      element = document.createElement("div");
    }
    element.addEventListener("focus", () => act(element.dataset.node, "focus"));
    return element;
  }

  function setAttr(element, name, value) {
    if (value === undefined || value === null || value === false) {
      element.removeAttribute(name);
    } else if (element.getAttribute(name) !== String(value)) {
      element.setAttribute(name, String(value));
    }
  }

  function apply(element, node, kind, offset) {
    element.dataset.node = node.id;
    element.id = `a11y-${node.id}`;
    const nativeRole = kind === "button" ? node.role === "button" : kind === "label";
    setAttr(element, "role",
      nativeRole || (kind === "container" && !CONTAINER_ROLES.has(node.role)) ? null : node.role);
    if (kind === "label") {
      if (element.textContent !== (node.name ?? "")) element.textContent = node.name ?? "";
    } else {
      setAttr(element, "aria-label", node.name);
    }
    setAttr(element, "aria-labelledby",
      !node.name && node.labelled_by ? node.labelled_by.map((id) => `a11y-${id}`).join(" ") : null);
    setAttr(element, "aria-description", node.description);
    setAttr(element, "aria-disabled", node.disabled ? "true" : null);
    setAttr(element, "aria-expanded", node.expanded === undefined ? null : String(node.expanded));
    setAttr(element, "aria-selected", node.selected === undefined ? null : String(node.selected));
    if (node.checked !== undefined) setAttr(element, "aria-checked", String(node.checked));
    if (kind === "range" || kind === "text") {
      const shown = node.value ?? (node.numeric ? String(node.numeric[0]) : "");
      if (document.activeElement !== element && element.value !== shown) element.value = shown;
      if (node.numeric) {
        setAttr(element, "aria-valuenow", node.numeric[0]);
        setAttr(element, "aria-valuemin", node.numeric[1]);
        setAttr(element, "aria-valuemax", node.numeric[2]);
      }
      element.readOnly = !!node.disabled;
    }
    if (kind !== "label" && kind !== "container") {
      element.tabIndex = node.disabled ? -1 : 0;
    } else if (node.focusable) {
      element.tabIndex = -1;
    }
    // Placed only when the place changed (each style write costs the browser a layout).
    const place = node.bounds
      ? `left:${node.bounds[0] - offset[0]}px;top:${node.bounds[1] - offset[1]}px;`
        + `width:${node.bounds[2]}px;height:${node.bounds[3]}px`
      : "";
    if (element.dataset.place !== place) {
      element.dataset.place = place;
      element.style.cssText = place;
      element.classList.toggle("placed", !!node.bounds);
    }
  }

  // The tree arrives inside the editor's frame: the DOM is brought up to date after it, when
  // the browser is idle (the latest tree only).
  let waiting = null;
  function update(json) {
    const first = waiting === null;
    waiting = json;
    if (!first) return;
    const run = () => {
      const latest = waiting;
      waiting = null;
      applyTree(latest);
    };
    if (window.requestIdleCallback) window.requestIdleCallback(run, { timeout: 200 });
    else setTimeout(run, 0);
  }

  function applyTree(json) {
    const started = performance.now();
    let tree;
    try {
      tree = JSON.parse(json);
    } catch {
      return;
    }
    const rect = canvas.getBoundingClientRect();
    const frame = `left:${rect.left}px;top:${rect.top}px;width:${rect.width}px;height:${rect.height}px`;
    if (root.dataset.place !== frame) {
      root.dataset.place = frame;
      root.style.cssText = frame;
    }
    const byId = new Map(tree.nodes.map((node) => [node.id, node]));
    const seen = new Set();
    // Depth first from the root, each element under its parent in reading order; absolute
    // places are taken from the nearest placed ancestor.
    const visit = (id, parent, offset) => {
      const node = byId.get(id);
      if (!node || seen.has(id)) return;
      seen.add(id);
      const kind = kindOf(node);
      let element = elements.get(id);
      if (!element || kinds.get(id) !== kind) {
        element?.remove();
        element = create(node, kind);
        elements.set(id, element);
        kinds.set(id, kind);
      }
      apply(element, node, kind, offset);
      if (element.parentNode !== parent) parent.append(element);
      const childOffset = node.bounds ? [node.bounds[0], node.bounds[1]] : offset;
      let previous = null;
      for (const child of node.children ?? []) {
        visit(child, element, childOffset);
        const childElement = elements.get(child);
        if (!childElement || childElement.parentNode !== element) continue;
        const expected = previous ? previous.nextSibling : element.firstChild;
        if (childElement !== expected) element.insertBefore(childElement, expected);
        previous = childElement;
      }
    };
    // The root window itself is the region: its children go straight under it.
    const rootNode = byId.get(tree.root);
    seen.add(tree.root);
    for (const child of rootNode?.children ?? []) visit(child, root, [0, 0]);
    for (const [id, element] of elements) {
      if (!seen.has(id)) {
        element.remove();
        elements.delete(id);
        kinds.delete(id);
      }
    }
    // Keep the page's focus on egui's focused widget while the user works from the keyboard.
    const focused = elements.get(tree.focus);
    const following = root.contains(document.activeElement)
      || (document.activeElement === canvas && tabbedOnCanvas);
    if (focused && tree.focus !== lastFocus && following && document.activeElement !== focused) {
      focused.focus({ preventScroll: true });
    }
    lastFocus = tree.focus;
    root.dataset.focus = `a11y-${tree.focus}`;
    // How long the last update took (ms; read by the end-to-end test).
    root.dataset.updateMs = (performance.now() - started).toFixed(2);
  }

  return { update, root };
}
