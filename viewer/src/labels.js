// Object label decluttering (issue 39): close objects (cups, books and a laptop on a table) put
// their labels on top of each other. After every render the labels are placed in priority order
// (the hovered object first, then larger boxes, then more confident objects) and a label whose
// screen rectangle overlaps one already placed is hidden (visibility: hidden, so it keeps its
// layout and can be measured next frame). Zooming in spreads the labels apart and brings the
// hidden ones back; hovering a box shows its label on top of the others.

const PADDING_PX = 2;

// Priority of an object's label: box volume (m³), then confidence.
export function labelPriority(object, extent) {
  const volume = Array.isArray(extent) ? Math.abs(extent[0] * extent[1] * extent[2]) : 0;
  const confidence = Number.isFinite(object.confidence) ? object.confidence : 0;
  return [volume, confidence];
}

function before(a, b) {
  if (a.hovered !== b.hovered) return a.hovered ? -1 : 1;
  for (let k = 0; k < a.priority.length; ++k) if (a.priority[k] !== b.priority[k]) return b.priority[k] - a.priority[k];
  return a.order - b.order;
}

function overlaps(r, placed) {
  return placed.some((p) => r.left < p.right + PADDING_PX && r.right > p.left - PADDING_PX &&
    r.top < p.bottom + PADDING_PX && r.bottom > p.top - PADDING_PX);
}

// entries: [{ element, priority: [..], order, hovered }]. Returns { shown, hidden, rects } (rects:
// the shown labels' page rectangles).
export function declutterLabels(entries) {
  // Every rectangle first (one layout), then the decisions and class changes (visibility does
  // not move anything, so the rectangles stay valid).
  const measured = [...entries].sort(before).map((e) => ({
    e, r: e.element.style.display === 'none' ? null : e.element.getBoundingClientRect(),  // none: behind the camera, layer off
  }));
  const placed = [];
  let hidden = 0;
  for (const { e, r } of measured) {
    e.element.classList.toggle('label-hover', Boolean(e.hovered));
    if (!r || (r.width === 0 && r.height === 0)) continue;
    const hide = !e.hovered && overlaps(r, placed);
    e.element.classList.toggle('label-hidden', hide);
    if (hide) ++hidden;
    else placed.push({ left: r.left, right: r.right, top: r.top, bottom: r.bottom });
  }
  return { shown: placed.length, hidden, rects: placed };
}
