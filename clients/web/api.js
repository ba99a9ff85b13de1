// HTTP to Strata: the token (sessionStorage, this tab only), JSON requests with If-Match, and
// problem documents (RFC 9457) turned into readable errors.

const TOKEN_KEY = 'strata.token';

/// The named scene this page shows (?scene=NAME), or null for the default scene.
export const SCENE = new URLSearchParams(location.search).get('scene');

/// `path` in the page's scene: /v1/X as /v1/scenes/NAME/X in a named scene.
export function scoped(path) {
  if (!SCENE || !path.startsWith('/v1/')) return path;
  return `/v1/scenes/${encodeURIComponent(SCENE)}/${path.slice(4)}`;
}

export function token() {
  return sessionStorage.getItem(TOKEN_KEY) || '';
}

export function setToken(value) {
  if (value) sessionStorage.setItem(TOKEN_KEY, value);
  else sessionStorage.removeItem(TOKEN_KEY);
}

/// An answer other than 2xx: `status`, the problem document (or null) and a one-line message.
export class ApiError extends Error {
  constructor(status, problem, text) {
    const detail = problem && (problem.detail || problem.title);
    super(`${status}${detail ? ': ' + detail : text ? ': ' + text.slice(0, 200) : ''}`);
    this.status = status;
    this.problem = problem;
    this.etag = null;
  }
}

/// fetch() with the token and JSON; resolves to {doc, etag (a number or null), response}.
export async function api(path, { method = 'GET', body, ifMatch } = {}) {
  const headers = {};
  if (token()) headers.Authorization = 'Bearer ' + token();
  if (body !== undefined) headers['Content-Type'] = 'application/json';
  if (ifMatch !== undefined && ifMatch !== null) headers['If-Match'] = `"${ifMatch}"`;
  const response = await fetch(scoped(path), {
    method, headers, body: body === undefined ? undefined : JSON.stringify(body),
  });
  const text = await response.text();
  let doc = null;
  try { doc = text ? JSON.parse(text) : null; } catch { doc = null; }
  const tag = response.headers.get('ETag');
  const etag = tag ? Number(tag.replace(/"/g, '')) : null;
  if (!response.ok) {
    const error = new ApiError(response.status, doc, text);
    error.etag = etag;  // a 412 names the current version
    throw error;
  }
  return { doc, etag, response };
}

/// A URL for <img> and EventSource, which cannot send headers: the token as ?access_token=.
export function withToken(path, params = {}) {
  const q = new URLSearchParams(params);
  if (token()) q.set('access_token', token());
  const s = q.toString();
  return s ? `${scoped(path)}?${s}` : scoped(path);
}

/// Applies one edit batch, conditional on `version` (If-Match) when given.
export function edit(edits, version) {
  return api('/v1/edits', { method: 'POST', body: { edits }, ifMatch: version });
}

/// Takes back the newest batch on the undo stack (POST /v1/undo), or with `redo` applies the
/// newest undone one again (POST /v1/redo), conditional on `version` (If-Match) when given.
export function undo(redo, version) {
  return api(redo ? '/v1/redo' : '/v1/undo', { method: 'POST', ifMatch: version });
}

/// `run` (async) wrapped so that calls while it runs coalesce into one more run after it: what
/// the last call asked for is what ends up shown, and a burst of calls costs two runs.
export function coalesced(run) {
  let running = false;
  let again = false;
  const call = async () => {
    if (running) {
      again = true;
      return;
    }
    running = true;
    try {
      await run();
    } finally {
      running = false;
      if (again) {
        again = false;
        call();
      }
    }
  };
  return call;
}

export function enc(id) {
  return encodeURIComponent(id);
}
