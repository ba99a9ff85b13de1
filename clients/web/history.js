// The history panel: the newest versions of the scene (GET /v1/history), each with what made it
// (an edit, or an undo or redo of an earlier version), its message, its op counts and when, and
// Undo and Redo buttons that name the version they would take back or apply again. Fetched again
// whenever the viewer sees the scene's version change. Every entry is an <li data-version
// data-kind>, marked `undoable` while it is on the undo stack, with a View button that shows the
// scene as that version left it.

import { api, coalesced } from './api.js';

/// Versions listed.
const SHOWN = 20;

/// "add_mesh ×2, set_transform" from {"add_mesh": 2, "set_transform": 1}.
function opCounts(ops) {
  const parts = Object.entries(ops || {}).map(([op, n]) => (n > 1 ? `${op} ×${n}` : op));
  return parts.length ? parts.join(', ') : 'no edits';
}

/// The entry's time of day in the viewer's time zone (the full UTC time is its tooltip).
function clock(time) {
  const t = new Date(time);
  return Number.isNaN(t.getTime()) ? time : t.toLocaleTimeString();
}

export class HistoryPanel {
  constructor(list, stacks, undoButton, redoButton, { onUndo, onRedo, onView }) {
    this.onView = onView;
    this.list = list;
    this.stacks = stacks;
    this.undoButton = undoButton;
    this.redoButton = redoButton;
    this.doc = null;  // GET /v1/history's answer
    this.refresh = coalesced(() => this.load());
    undoButton.addEventListener('click', () => onUndo());
    redoButton.addEventListener('click', () => onRedo());
  }

  /// Fetches the newest versions again (refresh(): calls during one coalesce into one more, so
  /// the last call's answer is the one shown).
  async load() {
    try {
      const { doc } = await api(`/v1/history?limit=${SHOWN}`);
      this.doc = doc;
      this.render();
    } catch (e) {
      this.doc = null;
      this.list.replaceChildren(this.note('Cannot read the history: ' + e.message));
      this.undoButton.disabled = this.redoButton.disabled = true;
    }
  }

  note(text) {
    const li = document.createElement('li');
    li.className = 'note';
    li.textContent = text;
    return li;
  }

  /// One version: "v12 · edit · its message" over "add_mesh ×2 · 17:02:03".
  entry(e) {
    const li = document.createElement('li');
    li.dataset.version = e.version;
    li.dataset.kind = e.kind;
    li.className = e.kind + (e.undoable ? ' undoable' : '');
    const what = e.kind === 'edit' ? 'edit' : `${e.kind} of v${e.target}`;
    const head = document.createElement('div');
    head.textContent = `v${e.version} · ${what}`;
    if (e.message) {
      const message = document.createElement('span');
      message.className = 'history-message';
      message.textContent = ` · ${e.message}`;
      head.append(message);
    }
    const detail = document.createElement('div');
    detail.className = 'history-detail';
    detail.textContent = `${opCounts(e.ops)} · ${clock(e.time)}`;
    detail.title = e.time;
    // The scene as this version left it, rendered from the data directory (at_version).
    const view = document.createElement('button');
    view.className = 'view';
    view.textContent = 'View';
    view.title = `Show the scene as it was at version ${e.version}`;
    view.addEventListener('click', () => this.onView(e.version));
    head.prepend(view);
    li.append(head, detail);
    if (this.doc.undo.next === e.version) li.title = 'Undo (Ctrl+Z) takes this version back';
    return li;
  }

  render() {
    const d = this.doc;
    this.list.replaceChildren(...d.entries.map((e) => this.entry(e)));
    if (!d.entries.length) this.list.append(this.note('No versions yet.'));
    else if (d.next_cursor) this.list.append(this.note(`older versions not shown (oldest: v${d.oldest})`));
    this.stacks.textContent = `undo ${d.undo.depth} · redo ${d.redo.depth}`;
    this.undoButton.disabled = d.undo.next === null;
    this.redoButton.disabled = d.redo.next === null;
    this.undoButton.title = d.undo.next === null
      ? 'Nothing to undo' : `Take back version ${d.undo.next} (Ctrl+Z)`;
    this.redoButton.title = d.redo.next === null
      ? 'Nothing to redo' : `Apply version ${d.redo.next} again (Ctrl+Shift+Z or Ctrl+Y)`;
    this.list.dataset.version = d.version;
  }
}
