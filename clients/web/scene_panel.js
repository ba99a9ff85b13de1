// The scene panel: groups, then instances, from the paginated listings (GET /v1/scene/groups,
// GET /v1/scene/instances), searchable by id (filtered as pages arrive); a click selects.

import { api } from './api.js';

const PAGE = 200;

export class ScenePanel {
  constructor(list, search, more, { onSelect }) {
    this.list = list;
    this.search = search;
    this.more = more;
    this.onSelect = onSelect;
    this.items = [];
    this.cursor = null;
    this.kind = 'groups';  // the listing the next page comes from
    this.selected = null;
    this.selectedKind = null;
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
    await this.page();
  }

  /// The next page: groups first, then instances once the groups are all listed.
  async page() {
    const q = new URLSearchParams({ limit: PAGE });
    if (this.cursor) q.set('cursor', this.cursor);
    try {
      const { doc } = await api(`/v1/scene/${this.kind}?` + q);
      this.items.push(...doc.items.map((i) => this.kind === 'groups'
        ? { kind: 'group', id: i.id, label: `${i.id}  ·  group${i.world_visible ? '' : '  (hidden)'}` }
        : { kind: 'instance', id: i.id, label: `${i.id}  ·  ${i.mesh}${i.world_visible ? '' : '  (hidden)'}` }));
      this.cursor = doc.next_cursor;
      if (!this.cursor && this.kind === 'groups') {
        this.kind = 'instances';
        if (this.items.length < PAGE) return this.page();
        this.cursor = '';
      }
    } catch (e) {
      this.cursor = null;
      this.list.textContent = `Cannot list ${this.kind}: ` + e.message;
      return;
    }
    this.render();
  }

  mark(id, kind) {
    this.selected = id;
    this.selectedKind = kind;
    for (const li of this.list.children) {
      li.classList.toggle('selected', li.dataset.id === id && li.dataset.kind === kind);
    }
  }

  render() {
    const needle = this.search.value.trim().toLowerCase();
    this.list.replaceChildren();
    for (const item of this.items) {
      if (needle && !item.id.toLowerCase().includes(needle)) continue;
      const li = document.createElement('li');
      li.dataset.id = item.id;
      li.dataset.kind = item.kind;
      li.className = item.kind;
      li.textContent = (item.kind === 'group' ? '▸ ' : '') + item.label;
      li.classList.toggle('selected', item.id === this.selected && item.kind === this.selectedKind);
      li.onclick = () => this.onSelect(item.id, item.kind);
      this.list.append(li);
    }
    this.more.hidden = this.cursor === null;
  }
}
