/**
 * Editing a finished dance in the page (issue 44), beside the viewer: choose a part of the
 * dance on the timeline (drag along the strip under it, mark the playhead, or type the
 * seconds), make it new as a new version of the job, and list, open and compare the versions
 * of the dance.
 *
 * Server API used (relative to the page):
 *   GET  api/systems              → which systems edit (`edit: {regenerate, keep}` per system)
 *   POST api/jobs                 multipart `params` only: {seed, edit: {of, variation,
 *                                 regenerate: [[from, to]], keep?}} → 202 {id} | 4xx {error, field}
 *                                 or {seed, end, edit: {of, variation, continue: true}}
 *   GET  api/jobs/<id>/versions   → {versions: [{id, number, state, seed, edit?, created}]}
 *
 * Times are seconds from the dance's start (the clock the viewer shows), as `edit.regenerate`
 * takes them.
 */
import { formatTime } from './viewer.js';
import { owned, rememberOwner } from './owner.js';

const $ = (id) => document.getElementById(id);

/** Shortest part the server makes new (`dancegen_generate::edit::MIN_RANGE_SECONDS`). */
const MIN_PART_S = 0.5;

/** Rounds to the tenth of a second the inputs show. */
const tenth = (s) => Math.round(s * 10) / 10;

/** What a version changed, in words: "3.0–6.0 s made new, arms kept". */
export function describeEdit(edit) {
  if (!edit) return 'the first dance';
  if (edit.continue && !(edit.regenerate ?? []).length) return 'continued';
  const parts = (edit.regenerate ?? []).map(([a, b]) => `${formatTime(a)}–${formatTime(b)}`).join(', ');
  const keep = edit.keep ? `, ${edit.keep} kept` : '';
  const of = edit.variation ? ` of variation ${edit.variation + 1}` : '';
  return `${parts} made new${of}${keep}`;
}

/** The versions of the dance job `id` belongs to, oldest first (empty if the server has none). */
export async function fetchVersions(id) {
  const res = await fetch(`api/jobs/${encodeURIComponent(id)}/versions`);
  if (!res.ok) return [];
  const body = await res.json();
  return Array.isArray(body.versions) ? body.versions : [];
}

/**
 * The edit box and the versions list of one open job. `page` gives the page's helpers:
 * `notice(text)`, `clearNotice()`, `markField(field)` and `open(url)` (navigates in the app).
 */
export class EditPanel {
  constructor(job, viewer, page) {
    this.job = job;
    this.viewer = viewer;
    this.page = page;
    this.abort = new AbortController();
    this.box = $('edit-box');
    this.from = $('edit-from');
    this.to = $('edit-to');
    this.band = $('selection');
    this.track = $('range-track');
    this.ready = this.setup();
  }

  /** Shows the box when the job's system edits, and the versions list. */
  async setup() {
    const system = await this.systemInfo();
    if (this.abort.signal.aborted) return;
    const edit = system?.edit ?? {};
    this.box.hidden = !edit.regenerate;
    $('edit-keep-field').hidden = !edit.keep;
    $('edit-keep').value = '';
    $('continue-fields').hidden = !edit.continue;
    if (edit.regenerate) this.wire();
    await this.showVersions();
  }

  async systemInfo() {
    try {
      const res = await fetch('api/systems');
      if (!res.ok) return null;
      const body = await res.json();
      const list = Array.isArray(body) ? body : body.systems ?? [];
      return list.find((s) => s.name === this.job.params?.system) ?? null;
    } catch {
      return null;
    }
  }

  wire() {
    const on = (el, type, fn) => el.addEventListener(type, fn, { signal: this.abort.signal });
    const p = this.job.params ?? {};
    const duration = this.viewer.duration;
    for (const input of [this.from, this.to]) {
      input.max = String(tenth(duration));
      input.value = '';
      on(input, 'input', () => this.showSelection());
    }
    // A new seed by default: the first one no variation of this job used.
    $('edit-seed').value = String((Number(p.seed) || 0) + Math.max(1, Number(p.variations) || 1));
    const variations = this.job.variations ?? [];
    const select = $('edit-variation');
    select.replaceChildren(...variations.map((v, i) => new Option(`Variation ${i + 1} · seed ${v.seed}`, String(i))));
    $('edit-variation-field').hidden = variations.length < 2;
    // Dragging along the strip under the timeline chooses the part.
    this.track.hidden = false;
    let anchor = null;
    const timeAt = (e) => {
      const r = this.track.getBoundingClientRect();
      const u = Math.min(Math.max((e.clientX - r.left) / Math.max(r.width, 1), 0), 1);
      return tenth(u * duration);
    };
    const choose = (a, b) => {
      this.from.value = String(Math.min(a, b));
      this.to.value = String(Math.max(a, b));
      this.showSelection();
    };
    on(this.track, 'pointerdown', (e) => {
      this.track.setPointerCapture(e.pointerId);
      anchor = timeAt(e);
      choose(anchor, anchor);
    });
    on(this.track, 'pointermove', (e) => { if (anchor !== null) choose(anchor, timeAt(e)); });
    on(this.track, 'pointerup', (e) => {
      if (anchor !== null) choose(anchor, timeAt(e));
      anchor = null;
    });
    on(this.track, 'pointercancel', () => { anchor = null; });
    on($('mark-from'), 'click', () => this.mark(this.from));
    on($('mark-to'), 'click', () => this.mark(this.to));
    on($('regenerate'), 'click', () => this.regenerate());
    // Continue: by default 10 s more, or to the song's end.
    const songEnd = this.viewer.audio.duration;
    const danceEnd = this.viewer.start + duration;
    const more = $('continue-to');
    more.min = String(tenth(danceEnd + MIN_PART_S));
    if (Number.isFinite(songEnd)) more.max = String(tenth(songEnd));
    more.value = String(tenth(Number.isFinite(songEnd) ? Math.min(songEnd, danceEnd + 10) : danceEnd + 10));
    on($('continue'), 'click', () => this.extend());
    this.showSelection();
  }

  /** Puts the playhead's time into `input` (and keeps from before to). */
  mark(input) {
    input.value = String(tenth(this.viewer.danceTime()));
    const [a, b] = [Number(this.from.value), Number(this.to.value)];
    if (this.from.value !== '' && this.to.value !== '' && a > b) {
      [this.from.value, this.to.value] = [this.to.value, this.from.value];
    }
    this.showSelection();
  }

  /** The chosen part as a band over the timeline (the slider spans the dance). */
  showSelection() {
    const d = this.viewer.duration;
    const [a, b] = [Number(this.from.value), Number(this.to.value)];
    const ok = this.from.value !== '' && this.to.value !== '' && d > 0 && a < b;
    this.band.hidden = !ok;
    if (!ok) return;
    const pct = (s) => `${(100 * Math.min(Math.max(s, 0), d)) / d}%`;
    this.band.style.left = pct(a);
    this.band.style.width = `calc(${pct(b)} - ${pct(a)})`;
    this.band.title = `${formatTime(a)} – ${formatTime(b)} will be made new`;
  }

  /** Continues the dance to the chosen time of the song, as a new version. */
  async extend() {
    this.page.clearNotice();
    const end = Number($('continue-to').value);
    const danceEnd = this.viewer.start + this.viewer.duration;
    if (!(end >= danceEnd + MIN_PART_S)) {
      this.page.notice(`The dance ends at ${formatTime(danceEnd)} of the song; continue it to at least ${formatTime(danceEnd + MIN_PART_S)}.`);
      $('continue-to').setAttribute('aria-invalid', 'true');
      return;
    }
    $('continue-to').removeAttribute('aria-invalid');
    const edit = { of: this.job.id, continue: true };
    const variation = Number($('edit-variation').value) || 0;
    if (variation > 0) edit.variation = variation;
    await this.send({ edit, end }, $('continue'), 'Continue the dance');
  }

  /** Submits `params` (plus the seed); the new version opens when it is accepted. */
  async send(params, button, label) {
    const seed = Number($('edit-seed').value);
    if (Number.isInteger(seed) && seed >= 0) params.seed = seed;
    const body = new FormData();
    body.append('params', JSON.stringify(params));
    button.disabled = true;
    button.textContent = 'Sending…';
    try {
      const res = await fetch('api/jobs', owned({ method: 'POST', body }));
      const reply = await res.json().catch(() => ({}));
      rememberOwner(reply);
      if (!res.ok) {
        this.page.notice(`The new version was refused: ${reply.error ?? `HTTP ${res.status}`}`);
        return;
      }
      this.page.open(`?job=${encodeURIComponent(reply.id)}`);
    } catch (e) {
      this.page.notice(`The edit did not reach the server (${e.message}). Is \`dancegen serve\` still running?`);
    } finally {
      button.disabled = false;
      button.textContent = label;
    }
  }

  /** Checks the part, then submits the edit; the new version opens when it is accepted. */
  async regenerate() {
    this.page.clearNotice();
    this.page.markField(null);
    const fail = (message, id) => {
      this.page.notice(message);
      if (id) {
        $(id).setAttribute('aria-invalid', 'true');
        $(id).focus();
      }
    };
    const [a, b] = [Number(this.from.value), Number(this.to.value)];
    const d = this.viewer.duration;
    if (this.from.value === '' || !(a >= 0)) return fail('Mark where the new part starts (or type the seconds).', 'edit-from');
    if (this.to.value === '' || !(b > a)) return fail('Mark where the new part ends, after its start.', 'edit-to');
    if (b > d + 0.05) return fail(`The dance is ${formatTime(d)} long; the part must end inside it.`, 'edit-to');
    if (b - a < MIN_PART_S) return fail(`The part is ${(b - a).toFixed(1)} s; make it at least ${MIN_PART_S} s.`, 'edit-to');
    for (const id of ['edit-from', 'edit-to']) $(id).removeAttribute('aria-invalid');
    const edit = { of: this.job.id, regenerate: [[a, Math.min(b, d)]] };
    const variation = Number($('edit-variation').value) || 0;
    if (variation > 0) edit.variation = variation;
    const keep = $('edit-keep').value;
    if (keep && !$('edit-keep-field').hidden) edit.keep = keep;
    await this.send({ edit }, $('regenerate'), 'Regenerate this part');
  }

  /** The versions of this dance, each to open or to compare with the open one. */
  async showVersions() {
    const versions = await fetchVersions(this.job.id);
    if (this.abort.signal.aborted) return;
    renderVersions(versions, this.job.id, null, this.page);
  }

  dispose() {
    this.abort.abort();
    this.box.hidden = true;
    this.band.hidden = true;
    this.track.hidden = true;
    $('versions-box').hidden = true;
    $('version-list').replaceChildren();
  }
}

/**
 * Lists `versions` in #versions-box (hidden when there is only one): the open one (`current`,
 * and `compared` when two are side by side) marked, the others with "Open" and "Compare".
 */
export function renderVersions(versions, current, compared, page) {
  const list = $('version-list');
  list.replaceChildren();
  $('versions-box').hidden = versions.length < 2;
  for (const v of versions) {
    const li = document.createElement('li');
    li.dataset.job = v.id;
    const shown = v.id === current || v.id === compared;
    if (shown) li.setAttribute('aria-current', 'true');
    const state = v.state === 'done' ? '' : ` (${v.state})`;
    li.append(`Version ${v.number} · seed ${v.seed} · ${describeEdit(v.edit)}${state}`);
    const actions = document.createElement('span');
    actions.className = 'version-actions';
    const link = (text, href, cls) => {
      const a = document.createElement('a');
      a.className = `button download ${cls}`;
      a.href = href;
      a.textContent = text;
      a.addEventListener('click', (e) => { e.preventDefault(); page.open(href); });
      return a;
    };
    if (!shown) actions.append(link('Open', `?job=${encodeURIComponent(v.id)}`, 'open-version'));
    if (!shown && v.state === 'done') {
      actions.append(link('Compare side by side', `?job=${encodeURIComponent(current)}&compare=${encodeURIComponent(v.id)}`, 'compare-version'));
    }
    if (actions.childElementCount) li.append(actions);
    list.append(li);
  }
}
