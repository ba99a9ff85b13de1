// The scene panel: groups, then instances, from the paginated listings (GET /v1/scene/groups,
// GET /v1/scene/instances), searchable by id (filtered as pages arrive), listed again after each
// commit that changed the scene; a click selects.

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

  /// One page into `s` ({items, cursor, kind}): groups first, then instances once the groups
  /// are all listed (cursor '' then means "instances from the start").
  async fetchPage(s) {
    const q = new URLSearchParams({ limit: PAGE });
    if (s.cursor) q.set('cursor', s.cursor);
    const { doc } = await api(`/v1/scene/${s.kind}?` + q);
    // A display name, when the object has one, comes before its id.
    const named = (i) => (i.name ? `${i.name}  ·  ` : '') + i.id;
    s.items.push(...doc.items.map((i) => s.kind === 'groups'
      ? { kind: 'group', id: i.id, name: i.name || '',
          label: `${named(i)}  ·  group${i.world_visible ? '' : '  (hidden)'}` }
      : { kind: 'instance', id: i.id, name: i.name || '',
          label: `${named(i)}  ·  ${i.mesh}${i.world_visible ? '' : '  (hidden)'}` }));
    s.cursor = doc.next_cursor;
    if (!s.cursor && s.kind === 'groups') {
      s.kind = 'instances';
      s.cursor = '';
    }
  }

  /// The next page (the "more" button).
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
  /// is complete. Calls during a refresh coalesce into one more.
  async refresh() {
    if (this.refreshing) {
      this.again = true;
      return;
    }
    this.refreshing = true;
    try {
      const want = Math.max(this.items.length, PAGE);
      const s = { items: [], cursor: null, kind: 'groups' };
      do {
        await this.fetchPage(s);
      } while (s.cursor !== null && s.items.length < want);
      Object.assign(this, s);
      this.render();
    } catch (e) {
      // Keep the list shown; the next commit tries again.
    } finally {
      this.refreshing = false;
      if (this.again) {
        this.again = false;
        this.refresh();
      }
    }
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
      if (needle && !`${item.id} ${item.name}`.toLowerCase().includes(needle)) continue;
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
