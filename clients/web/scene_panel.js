// The scene panel. Without a search: the scene graph as a tree (GET /v1/scene/tree), groups open
// with their children nested, each group foldable (▾/▸). With a search: groups, then instances,
// from the paginated listings (GET /v1/scene/groups, GET /v1/scene/instances), filtered by id and
// display name as pages arrive. Both are fetched again after each commit that changed the scene;
// a click selects. Every entry is an <li data-kind data-id>.

import { api, coalesced } from './api.js';

const PAGE = 200;
/// Nodes of the tree fetched at once; a larger scene says so and the listings page the rest.
const TREE_NODES = 2000;

/// "Name  ·  id", or the id alone.
const named = (i) => (i.name ? `${i.name}  ·  ` : '') + i.id;
const hidden = (i) => (i.world_visible ? '' : '  (hidden)');

export class ScenePanel {
  constructor(list, search, more, { onSelect }) {
    this.list = list;
    this.search = search;
    this.more = more;
    this.onSelect = onSelect;
    this.items = [];
    this.cursor = null;
    this.kind = 'groups';  // the listing the next page comes from
    this.tree = null;      // GET /v1/scene/tree's answer
    this.folded = new Set();  // ids of the groups shown folded
    this.selected = null;
    this.selectedKind = null;
    this.refresh = coalesced(() => this.load());
    let timer = null;
    search.addEventListener('input', () => {
      clearTimeout(timer);
      timer = setTimeout(() => this.render(), 100);
    });
    more.addEventListener('click', () => this.page());
  }

  async load() {
    this.items = [];
    this.cursor = null;
    this.kind = 'groups';
    await Promise.all([this.page(), this.fetchTree()]);
  }

  async fetchTree() {
    try {
      const { doc } = await api(`/v1/scene/tree?depth=64&max_nodes=${TREE_NODES}`);
      this.tree = doc;
    } catch (e) {
      this.tree = null;
    }
    this.render();
  }

  /// One page into `s` ({items, cursor, kind}): groups first, then instances once the groups
  /// are all listed (cursor '' then means "instances from the start").
  async fetchPage(s) {
    const q = new URLSearchParams({ limit: PAGE });
    if (s.cursor) q.set('cursor', s.cursor);
    const { doc } = await api(`/v1/scene/${s.kind}?` + q);
    s.items.push(...doc.items.map((i) => s.kind === 'groups'
      ? { kind: 'group', id: i.id, name: i.name || '', label: `${named(i)}  ·  group${hidden(i)}` }
      : { kind: 'instance', id: i.id, name: i.name || '',
          label: `${named(i)}  ·  ${i.mesh}${hidden(i)}` }));
    s.cursor = doc.next_cursor;
    if (!s.cursor && s.kind === 'groups') {
      s.kind = 'instances';
      s.cursor = '';
    }
  }

  /// The next page of the listings (the "more" button).
  async page() {
    const s = { items: this.items, cursor: this.cursor, kind: this.kind };
    try {
      await this.fetchPage(s);
      // A short group list is followed by the first instances at once.
      if (s.kind === 'instances' && s.cursor === '' && s.items.length < PAGE) await this.fetchPage(s);
    } catch (e) {
      this.cursor = null;
      this.list.textContent = `Cannot list ${this.kind}: ` + e.message;
      return;
    }
    Object.assign(this, s);
    this.render();
  }

  /// Lists the scene again after a commit (another client may have added, removed or hidden
  /// something), as far as the pages shown so far reached; the old list stays until the new one
  /// is complete (refresh(): calls during one coalesce into one more).
  async load() {
    try {
      const want = Math.max(this.items.length, PAGE);
      const s = { items: [], cursor: null, kind: 'groups' };
      do {
        await this.fetchPage(s);
      } while (s.cursor !== null && s.items.length < want);
      const { doc } = await api(`/v1/scene/tree?depth=64&max_nodes=${TREE_NODES}`);
      Object.assign(this, s);
      this.tree = doc;
      this.render();
    } catch (e) {
      // Keep the list shown; the next commit tries again.
    }
  }

  mark(id, kind) {
    this.selected = id;
    this.selectedKind = kind;
    for (const li of this.list.querySelectorAll('li')) {
      li.classList.toggle('selected', li.dataset.id === id && li.dataset.kind === kind);
    }
  }

  /// One entry; a click selects it (and not the groups it is nested in).
  entry(kind, id, label) {
    const li = document.createElement('li');
    li.dataset.id = id;
    li.dataset.kind = kind;
    li.className = kind;
    const text = document.createElement('span');
    text.textContent = label;
    li.append(text);
    li.classList.toggle('selected', id === this.selected && kind === this.selectedKind);
    li.onclick = (e) => {
      e.stopPropagation();
      this.onSelect(id, kind);
    };
    return li;
  }

  /// The groups and instances of one tree node into `ul`, groups with their own children.
  treeNodes(node, ul) {
    for (const g of node.groups || []) {
      const li = this.entry('group', g.id, `${named(g)}${hidden(g)}`);
      const fold = document.createElement('span');
      fold.className = 'fold';
      const open = !this.folded.has(g.id);
      fold.textContent = (g.group_count + g.instance_count === 0) ? '· ' : open ? '▾ ' : '▸ ';
      fold.onclick = (e) => {
        e.stopPropagation();
        if (open) this.folded.add(g.id); else this.folded.delete(g.id);
        this.render();
      };
      li.prepend(fold);
      ul.append(li);
      if (!open) continue;
      const children = document.createElement('ul');
      this.treeNodes(g, children);
      const listed = (g.groups || []).length + (g.instances || []).length;
      if (listed < g.group_count + g.instance_count) {
        const rest = document.createElement('li');
        rest.className = 'note';
        rest.textContent = `${g.group_count + g.instance_count - listed} more (search to find them)`;
        children.append(rest);
      }
      if (children.children.length) li.append(children);
    }
    for (const i of node.instances || []) {
      ul.append(this.entry('instance', i.id, `${named(i)}  ·  ${i.mesh}${hidden(i)}`));
    }
  }

  render() {
    const needle = this.search.value.trim().toLowerCase();
    this.list.replaceChildren();
    if (!needle && this.tree) {
      this.treeNodes(this.tree, this.list);
      if (this.tree.truncated) {
        const note = document.createElement('li');
        note.className = 'note';
        note.textContent = `the scene has more than ${TREE_NODES} nodes: search to find the others`;
        this.list.append(note);
      }
      this.more.hidden = true;
      return;
    }
    for (const item of this.items) {
      if (needle && !`${item.id} ${item.name}`.toLowerCase().includes(needle)) continue;
      this.list.append(this.entry(item.kind, item.id,
                                  (item.kind === 'group' ? '▸ ' : '') + item.label));
    }
    this.more.hidden = this.cursor === null;
  }
}
