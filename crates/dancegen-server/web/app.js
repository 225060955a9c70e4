/**
 * The page's controller: which view shows (the form at `/`, a job at `/?job=<id>`), the
 * submit form, and a job's live progress; the 3D viewer itself is viewer.js.
 *
 * Written for someone who has never used a terminal: every failure is shown in words on the
 * page (server unreachable, upload rejected with the server's own reason, job failed or
 * cancelled, 3D file not loadable), never only in the console.
 *
 * Server API used (all relative to the page, so the app also works behind a path prefix):
 *   GET    api/systems          → {systems: [{name, available, error?, genres, default_genre,
 *                               dancers: {min, max}, needs_leader}], limits: {upload_bytes}}
 *                               (a bare array of systems, or fields left out, also work)
 *   POST   api/jobs             multipart: params (JSON text), song (file), leader (file, duet),
 *                                character (file, optional: solo and holistic)
 *                               → 202 {id} | 4xx {error, field?}
 *   GET    api/jobs/<id>/events Server-Sent Events, each `data:` the job JSON (on connect and on
 *                               every change)
 *   GET    api/jobs/<id>        the job JSON (used when the event stream is refused)
 *   DELETE api/jobs/<id>        cancel
 *   GET    api/jobs/<id>/zip    every dance file in one zip, under the names they download as
 *   (editing and versions: edit.js)
 *
 * URLs: `/?job=<id>` a job; `/?job=<id>&compare=<other>` two versions of a dance side by side.
 */
import { Viewer, downloadLinks } from './viewer.js';
import { EditPanel, fetchVersions, renderVersions } from './edit.js';
import { Library, STATE_WORDS, againHref, danceTitle } from './library.js';
import { owned, rememberOwner } from './owner.js';

const $ = (id) => document.getElementById(id);

/** Friendly names of the dance systems; the server's own `label` wins when it sends one. */
const SYSTEM_LABELS = {
  solo: 'Solo — one dancer',
  duet: 'Duet — partner for a leader',
  group: 'Group — 2 to 5 dancers',
  holistic: 'Holistic — hands and face',
};

/** What each job stage means to a user; unknown stages are shown by their own name. */
const STAGE_LABELS = {
  load_model: 'Loading the dance model',
  analyse_song: 'Listening to the song',
  choreography: 'Planning the choreography',
  denoising: 'Creating the movement',
  tokens: 'Creating the movement',
  render_video: 'Rendering the video',
  write_outputs: 'Saving the files',
  render_mp4: 'Making the video',
  preview: 'Making the video',
  done: 'Finishing',
};

const FINAL_STATES = new Set(['done', 'failed', 'cancelled']);

// ---------------------------------------------------------------------------------------------
// Test hooks. The browser test (tests/browser/viewer_check.mjs) opens /?job=<id> and awaits
// `window.__viewer.ready`; the object exists from the first moment so the test never races the
// page, and `ready` rejects (in words) if the job failed, was cancelled or a file did not load.

function deferred() {
  let resolve;
  let reject;
  const promise = new Promise((res, rej) => { resolve = res; reject = rej; });
  promise.catch(() => {}); // A rejection nobody awaits is not a console error.
  return { promise, resolve, reject };
}

let viewerReady = deferred();
/** The open viewer (a done job), or null. */
let viewer = null;
/** The open job's edit box and versions list (edit.js), or null. */
let editPanel = null;
/** The open job's event stream, or null. */
let events = null;

function openViewer() {
  if (!viewer) throw new Error('no dance is open in the viewer');
  return viewer;
}

window.__viewer = {
  get ready() { return viewerReady.promise; },
  seek: (t) => openViewer().seek(t),
  joints: (v = 0) => openViewer().joints(v),
  figures: (v = 0) => openViewer().figures(v),
  timeline: () => openViewer().timelineInfo(),
  camera: () => openViewer().cameraInfo(),
  audio: () => openViewer().audio,
  play: () => openViewer().play(),
  count: () => openViewer().count,
  /** Resolves when the edit box and the versions list are shown. */
  edited: () => editPanel?.ready ?? Promise.resolve(),
};

// ---------------------------------------------------------------------------------------------
// Words on the page.

/** Shows `text`, and after it the link `link` (`{href, text}`) when given. */
function showNotice(text, kind = 'error', link = null) {
  const n = $('notice');
  n.textContent = text;
  if (link) {
    const a = document.createElement('a');
    a.href = link.href;
    a.textContent = link.text;
    n.append(' ', a);
  }
  n.dataset.kind = kind;
  n.hidden = false;
}

function clearNotice() {
  $('notice').hidden = true;
  $('notice').textContent = '';
}

/** The server's `{error}` words for a failed response, or a sentence about the status. */
async function responseError(res, what) {
  let body = null;
  try { body = await res.json(); } catch { /* not JSON */ }
  if (body && typeof body.error === 'string') return { message: body.error, field: body.field };
  if (res.status === 413) return { message: `${what}: the file is too large for this server.` };
  if (res.status === 404) return { message: `${what}: not found.` };
  return { message: `${what}: the server answered ${res.status} ${res.statusText}.` };
}

function formatEta(s) {
  if (s === null || s === undefined || !Number.isFinite(s)) return '';
  const secs = Math.max(1, Math.round(s));
  if (secs < 60) return `about ${secs} s left`;
  const m = Math.floor(secs / 60);
  const r = secs % 60;
  return r ? `about ${m} min ${r} s left` : `about ${m} min left`;
}

function stageLabel(stage) {
  if (!stage) return 'Starting';
  if (STAGE_LABELS[stage]) return STAGE_LABELS[stage];
  const words = String(stage).replace(/_/g, ' ');
  return words.charAt(0).toUpperCase() + words.slice(1);
}

/** A file size in words: bytes below 1 KB (an empty file is "0 B", not "1 KB"), then KB, MB. */
function formatSize(bytes) {
  if (bytes < 1024) return `${bytes} B`;
  if (bytes < 1024 * 1024) return `${Math.round(bytes / 1024)} KB`;
  return `${(bytes / 1024 / 1024).toFixed(1)} MB`;
}

// ---------------------------------------------------------------------------------------------
// Views.

/** Shows the view for the current URL: a job when `?job=<id>`, else the form. */
function route() {
  closeJob();
  clearNotice();
  const query = new URLSearchParams(location.search);
  const id = query.get('job');
  comparing = query.get('compare');
  $('submit-view').hidden = Boolean(id);
  $('job-view').hidden = !id;
  if (id) openJob(id);
  else {
    const again = query.get('again');
    showForm().then(() => again && fillFromJob(again));
    library.refresh();
  }
}

/**
 * "Try again" on a failed or cancelled dance: the form filled in with its settings and its
 * files (the song, a duet's leader, the character, fetched back from the server), so that the
 * user changes what made it fail and makes the dance.
 */
async function fillFromJob(id) {
  try {
    const res = await fetch(`api/jobs/${encodeURIComponent(id)}`);
    if (!res.ok) throw new Error((await responseError(res, 'Reading that dance')).message);
    const job = await res.json();
    const p = job.params ?? {};
    if (systems.has(p.system)) {
      $('system').value = p.system;
      systemChanged();
    }
    const set = (field, v) => { $(field).value = v === undefined || v === null ? '' : String(v); };
    if (p.dancers !== undefined) set('dancers', p.dancers);
    set('seed', p.seed ?? 0);
    if (p.genre) $('genre').value = p.genre;
    set('start', p.start);
    set('end', p.end);
    set('steps', p.steps);
    $('variations').value = String(p.variations ?? 1);
    $('mp4').checked = Boolean(p.mp4);
    $('video-size-field').hidden = !p.mp4;
    if (p.video_size) $('video-size').value = p.video_size;
    $('rig').value = p.rig ?? 'smpl';
    const files = job.files ?? {};
    const fetchFile = async (key, name) => {
      const r = await fetch(files[key]);
      if (!r.ok) throw new Error(`its file ${key} cannot be read (HTTP ${r.status})`);
      return new File([await r.blob()], name, { type: r.headers.get('content-type') ?? '' });
    };
    const put = (input, file) => {
      const list = new DataTransfer();
      list.items.add(file);
      $(input).files = list.files;
    };
    const ext = (key) => key.slice(key.lastIndexOf('.'));
    const songKey = Object.keys(files).find((k) => files[k] === job.song);
    if (!songKey) throw new Error('its song is not on the server any more');
    const song = await fetchFile(songKey, `${p.song_title ?? 'song'}${ext(songKey)}`);
    put('song', song);
    setSong(song);
    // The uploaded leader (leader.<ext>; a finished duet's leader.npy is the leader as danced).
    const leaderKey = Object.keys(files).find((k) => /^leader\.(bvh|fbx|glb|npz|pkl)$/.test(k))
      ?? (p.system === 'duet' && files['leader.npy'] ? 'leader.npy' : undefined);
    if (leaderKey) put('leader', await fetchFile(leaderKey, leaderKey));
    if (p.character && files[p.character]) put('character', await fetchFile(p.character, p.character));
    const what = STATE_WORDS[job.state] ?? job.state;
    showNotice(`The settings and files of that ${what} dance are filled in: change what you need, then press Make the dance.`, 'info');
  } catch (e) {
    showNotice(`The form could not be filled in from that dance: ${e.message}.`);
  }
}

/** "My dances", under the form. */
const library = new Library($('library'), (text) => showNotice(text));

function closeJob() {
  events?.close();
  events = null;
  editPanel?.dispose();
  editPanel = null;
  viewer?.dispose();
  viewer = null;
  viewerReady.reject(new Error('the page left this job'));
  viewerReady = deferred();
  $('viewer').hidden = true;
  $('all-files').hidden = true;
  $('download-all-box').hidden = true;
  $('job-warnings').hidden = true;
  $('file-list').replaceChildren();
  $('variations-box').replaceChildren();
  document.title = 'dancegen';
}

// ---------------------------------------------------------------------------------------------
// The form.

/** Systems as the server listed them, by name. */
let systems = new Map();
/** The server's limits (`upload_bytes`, …), as far as it told them. */
let limits = {};
let formWired = false;

async function showForm() {
  if (!formWired) {
    wireForm();
    formWired = true;
  }
  if (systems.size) return;
  try {
    const res = await fetch('api/systems');
    if (!res.ok) throw new Error((await responseError(res, 'Listing the dance systems')).message);
    const data = await res.json();
    const list = Array.isArray(data) ? data : data.systems ?? [];
    limits = (!Array.isArray(data) && data.limits) || {};
    systems = new Map(list.map((s) => [s.name ?? s.id, s]));
    fillSystems();
  } catch (e) {
    showNotice(`Cannot reach the dancegen server (${e.message}). Is \`dancegen serve\` still running?`);
  }
}

function fillSystems() {
  const select = $('system');
  select.replaceChildren();
  for (const [name, s] of systems) {
    const o = document.createElement('option');
    o.value = name;
    const available = s.available !== false;
    const why = s.error ? ' (no model installed on this server)' : ' (coming later)';
    o.textContent = (s.label ?? SYSTEM_LABELS[name] ?? name) + (available ? '' : why);
    o.disabled = !available;
    select.append(o);
  }
  const first = [...systems.values()].find((s) => s.available !== false);
  if (first) select.value = first.name ?? first.id;
  select.disabled = false;
  systemChanged();
}

/** What a system needs: a leader, and how many dancers it dances (from the server, or known). */
function systemNeeds(name) {
  const s = systems.get(name) ?? {};
  const leader = s.needs_leader ?? name === 'duet';
  const fallback = name === 'group' ? { min: 2, max: 5 } : name === 'duet' ? { min: 2, max: 2 } : { min: 1, max: 1 };
  const dancers = { ...fallback, ...(s.dancers ?? {}) };
  return { leader, dancers, chooseDancers: dancers.max > dancers.min };
}

/** Shows the fields that apply to the chosen system. */
function systemChanged() {
  const name = $('system').value;
  const s = systems.get(name) ?? {};
  const needs = systemNeeds(name);
  $('leader-field').hidden = !needs.leader;
  // A character dances alone: a duet's or a group's .glb holds several dancers.
  $('character-field').hidden = needs.dancers.max !== 1;
  $('dancers-field').hidden = !needs.chooseDancers;
  $('dancers').min = String(needs.dancers.min);
  $('dancers').max = String(needs.dancers.max);
  // A duet lasts as long as its leader.
  $('end-field').hidden = needs.leader;
  const genres = Array.isArray(s.genres) ? s.genres : [];
  $('genre-field').hidden = genres.length === 0;
  const g = $('genre');
  g.replaceChildren();
  const def = document.createElement('option');
  def.value = '';
  def.textContent = s.default_genre ? `Model's choice (${s.default_genre.replace(/_/g, ' ')})` : "Model's choice";
  g.append(def);
  for (const genre of genres) {
    const o = document.createElement('option');
    o.value = genre;
    o.textContent = genre.replace(/_/g, ' ');
    g.append(o);
  }
  $('system-hint').textContent = s.description ?? '';
}

function setSong(file) {
  const name = $('song-name');
  name.hidden = !file;
  name.textContent = file ? `${file.name} · ${formatSize(file.size)}` : '';
  $('drop-zone').classList.toggle('has-file', Boolean(file));
}

function wireForm() {
  const zone = $('drop-zone');
  const input = $('song');
  input.addEventListener('change', () => setSong(input.files[0]));
  // The zone is a tab stop: Enter and Space open the file picker, as a button's would.
  zone.addEventListener('keydown', (e) => {
    if (e.target !== zone || (e.key !== 'Enter' && e.key !== ' ')) return;
    e.preventDefault();
    input.click();
  });
  // A phone or tablet has no file to drag: say what to do there.
  if (matchMedia('(hover: none) and (pointer: coarse)').matches) {
    $('drop-words').textContent = 'Choose a song';
    $('drop-or').textContent = '(tap here)';
  }
  for (const type of ['dragenter', 'dragover']) {
    zone.addEventListener(type, (e) => { e.preventDefault(); zone.classList.add('dragging'); });
  }
  zone.addEventListener('dragleave', () => zone.classList.remove('dragging'));
  zone.addEventListener('drop', (e) => {
    e.preventDefault();
    zone.classList.remove('dragging');
    const files = e.dataTransfer?.files;
    if (!files?.length) return;
    input.files = files;
    setSong(files[0]);
    markField(null);
  });
  // A file dropped beside the zone would make the browser leave the page to open it.
  for (const type of ['dragover', 'drop']) {
    window.addEventListener(type, (e) => { if (!zone.contains(e.target)) e.preventDefault(); });
  }
  $('system').addEventListener('change', systemChanged);
  $('mp4').addEventListener('change', () => { $('video-size-field').hidden = !$('mp4').checked; });
  $('job-form').addEventListener('input', (e) => { if (e.target.getAttribute('aria-invalid')) markField(null); });
  $('job-form').addEventListener('submit', (e) => {
    e.preventDefault();
    submit();
  });
}

/** Highlights the form control the server (or the form) named, or clears the highlight. */
function markField(field) {
  for (const el of document.querySelectorAll('[aria-invalid="true"]')) el.removeAttribute('aria-invalid');
  if (!field) return;
  const el = $(field);
  if (!el) return;
  el.setAttribute('aria-invalid', 'true');
  el.closest('details')?.setAttribute('open', '');
  el.focus({ preventScroll: false });
}

/** Reads the form into `params` (optional fields left out when empty), or throws {message, field}. */
function readParams() {
  const fail = (message, field) => { throw Object.assign(new Error(message), { field }); };
  const system = $('system').value;
  if (!system || !systems.has(system)) fail('Choose a kind of dance.', 'system');
  const song = $('song').files[0];
  if (!song) fail('Choose a song first: drop it on the box or click the box.', 'song');
  if (song.size === 0) fail(`“${song.name}” is empty (0 B): choose a music file.`, 'song');
  const params = { system };
  const number = (id, { integer = false, min = 0, max = Infinity, label }) => {
    const raw = $(id).value.trim();
    if (raw === '') return undefined;
    const x = Number(raw);
    if (!Number.isFinite(x) || x < min || x > max || (integer && !Number.isInteger(x))) {
      const kind = integer ? 'a whole number' : 'a number';
      fail(`${label}: “${raw}” is not ${kind} from ${min}${max < Infinity ? ` to ${max}` : ' up'}.`, id);
    }
    return x;
  };
  if (limits.upload_bytes && song.size > limits.upload_bytes) {
    fail(`The song is ${formatSize(song.size)}; this server takes files up to ${formatSize(limits.upload_bytes)}.`, 'song');
  }
  const needs = systemNeeds(system);
  let leader;
  if (needs.leader) {
    leader = $('leader').files[0];
    if (!leader) fail("A duet needs the leader's motion: choose a BVH file.", 'leader');
  }
  if (needs.chooseDancers) {
    const { min, max } = needs.dancers;
    params.dancers = number('dancers', { integer: true, min, max, label: 'Dancers' });
    if (params.dancers === undefined) fail(`Dancers: choose ${min} to ${max}.`, 'dancers');
  }
  params.seed = number('seed', { integer: true, label: 'Seed' }) ?? 0;
  if (!$('genre-field').hidden && $('genre').value) params.genre = $('genre').value;
  const steps = number('steps', { integer: true, min: 1, max: 1000, label: 'Denoising steps' });
  if (steps !== undefined) params.steps = steps;
  const start = number('start', { label: 'Start' });
  if (start !== undefined) params.start = start;
  if (!needs.leader) {
    const end = number('end', { label: 'End' });
    if (end !== undefined) {
      if (start !== undefined && end <= start) fail(`End (${end} s) must come after start (${start} s).`, 'end');
      params.end = end;
    }
  }
  params.variations = number('variations', { integer: true, min: 1, max: 4, label: 'Variations' }) ?? 1;
  params.mp4 = $('mp4').checked;
  if (params.mp4) params.video_size = $('video-size').value;
  if ($('rig').value !== 'smpl') params.rig = $('rig').value;
  let character;
  if (!$('character-field').hidden) {
    character = $('character').files[0];
    if (character) {
      const ext = character.name.split('.').pop().toLowerCase();
      if (!['glb', 'vrm'].includes(ext) || !character.name.includes('.')) {
        fail(`“${character.name}” is not a .glb or .vrm: export your character as one .glb file with its skin.`, 'character');
      }
      if (character.size === 0) fail(`“${character.name}” is empty (0 B): choose your character's .glb.`, 'character');
      if (limits.upload_bytes && song.size + character.size > limits.upload_bytes) {
        fail(`The song and the character are ${formatSize(song.size + character.size)}; this server takes uploads up to ${formatSize(limits.upload_bytes)}.`, 'character');
      }
    }
  }
  return { params, song, leader, character };
}

async function submit() {
  clearNotice();
  markField(null);
  let form;
  try {
    form = readParams();
  } catch (e) {
    showNotice(e.message);
    markField(e.field);
    return;
  }
  const body = new FormData();
  // params first: the server can refuse bad parameters before the song has been uploaded.
  body.append('params', JSON.stringify(form.params));
  body.append('song', form.song, form.song.name);
  if (form.leader) body.append('leader', form.leader, form.leader.name);
  if (form.character) body.append('character', form.character, form.character.name);
  const button = $('submit');
  button.disabled = true;
  button.textContent = 'Uploading…';
  try {
    const res = await fetch('api/jobs', owned({ method: 'POST', body }));
    if (!res.ok) {
      const err = await responseError(res, 'The upload was refused');
      showNotice(err.message);
      markField(err.field);
      return;
    }
    const reply = await res.json();
    rememberOwner(reply);
    const { id } = reply;
    history.pushState(null, '', `?job=${encodeURIComponent(id)}`);
    route();
  } catch (e) {
    showNotice(`The upload did not reach the server (${e.message}). Is \`dancegen serve\` still running?`);
  } finally {
    button.disabled = false;
    button.textContent = 'Make the dance';
  }
}

// ---------------------------------------------------------------------------------------------
// A job: progress while it runs, then the viewer.

/** The version shown beside the open job (`&compare=<id>`), or null. */
let comparing = null;

/** What edit.js needs of the page. */
const page = {
  notice: (text) => showNotice(text),
  clearNotice: () => clearNotice(),
  markField: (field) => markField(field),
  open: (url) => {
    history.pushState(null, '', url);
    route();
  },
};

/** A done job: its viewer, or two versions side by side. */
async function showDone(job) {
  if (!comparing) {
    startViewer(job);
    return;
  }
  const other = comparing;
  let shown = job;
  try {
    const res = await fetch(`api/jobs/${encodeURIComponent(other)}`);
    const them = res.ok ? await res.json() : null;
    if (viewer || comparing !== other) return;
    if (!them || them.state !== 'done' || !them.variations?.length) {
      showNotice(them ? `Version ${other} is ${them.state}, so it cannot be compared yet.` : `There is no job ${other} to compare with (it may have been deleted).`);
    } else {
      const versions = await fetchVersions(job.id);
      const number = (id) => versions.find((v) => v.id === id)?.number;
      const label = (id) => (number(id) ? `Version ${number(id)}` : `Job ${id}`);
      shown = {
        ...job,
        variations: [
          { ...job.variations[0], label: label(job.id) },
          { ...them.variations[0], label: label(other) },
        ],
      };
      renderVersions(versions, job.id, other, page);
    }
  } catch (e) {
    showNotice(`Cannot reach the server to compare (${e.message}).`);
  }
  if (!viewer) startViewer(shown);
}

function openJob(id) {
  $('job-status').textContent = 'Connecting…';
  $('progress-box').hidden = false;
  $('job-progress').hidden = false;
  $('job-progress').removeAttribute('value');
  $('job-eta').textContent = '';
  const cancel = $('cancel');
  cancel.hidden = true;
  cancel.onclick = () => cancelJob(id);
  const url = `api/jobs/${encodeURIComponent(id)}`;
  const es = new EventSource(`${url}/events`);
  events = es;
  let final = false;
  es.onmessage = (e) => {
    let job;
    try { job = JSON.parse(e.data); } catch { return; }
    final = FINAL_STATES.has(job.state);
    // The job will not change any more: stop listening (the browser would reconnect).
    if (final) es.close();
    showJob(job);
  };
  es.onerror = async () => {
    if (final || events !== es) return;
    if (es.readyState !== EventSource.CLOSED) {
      $('job-eta').textContent = 'Connection to the server lost; reconnecting…';
      return;
    }
    // The stream was refused (an unknown job, say): ask once more for the reason in words.
    try {
      const res = await fetch(url);
      if (events !== es) return;
      if (res.ok) showJob(await res.json());
      else if (res.status === 404) {
        failJob('This dance is not on this server: it may have been deleted, or have expired.',
          { href: './#library', text: 'See My dances' });
      } else failJob((await responseError(res, `Job ${id}`)).message);
    } catch (err) {
      failJob(`Cannot reach the dancegen server (${err.message}).`);
    }
  };
}

function failJob(message, link = null) {
  $('job-status').textContent = 'Something went wrong.';
  $('job-progress').hidden = true;
  $('cancel').hidden = true;
  showNotice(message, 'error', link);
  viewerReady.reject(new Error(message));
}

async function cancelJob(id) {
  const cancel = $('cancel');
  cancel.disabled = true;
  try {
    const res = await fetch(`api/jobs/${encodeURIComponent(id)}`, owned({ method: 'DELETE' }));
    if (!res.ok) showNotice((await responseError(res, 'Cancelling')).message);
    else $('job-status').textContent = 'Cancelling…';
  } catch (e) {
    showNotice(`Cannot reach the server to cancel (${e.message}).`);
  } finally {
    cancel.disabled = false;
  }
}

/** Shows one state of the job (every SSE event). */
function showJob(job) {
  const status = $('job-status');
  const bar = $('job-progress');
  const eta = $('job-eta');
  const cancel = $('cancel');
  showFiles(job.files);
  showWarnings(job.warnings);
  // Every dance file in one zip, once the dance is finished (GET /api/jobs/{id}/zip).
  $('download-all-box').hidden = job.state !== 'done';
  $('download-all').href = `api/jobs/${encodeURIComponent(job.id)}/zip`;
  switch (job.state) {
    case 'queued': {
      const pos = job.queue_position;
      // queue_position: jobs ahead of this one (0 = next to run).
      const ahead = !Number.isInteger(pos) ? '' : pos === 0 ? ' — next in line' : ` — ${pos} ${pos === 1 ? 'dance' : 'dances'} ahead`;
      status.textContent = `Waiting in line${ahead}…`;
      bar.hidden = false;
      bar.removeAttribute('value');
      eta.textContent = formatEta(job.eta_s);
      cancel.hidden = false;
      document.title = 'dancegen — waiting';
      break;
    }
    case 'running': {
      const p = Math.min(Math.max(Number(job.progress) || 0, 0), 1);
      // Several variations run one after the other: say which one is being made.
      const n = Number(job.params?.variations) || 1;
      const k = Math.min(n, Math.floor(p * n) + 1);
      const which = n > 1 ? ` (variation ${k} of ${n})` : '';
      status.textContent = `${stageLabel(job.stage)}${which}… ${Math.floor(p * 100)} %`;
      bar.hidden = false;
      bar.value = p;
      eta.textContent = formatEta(job.eta_s);
      cancel.hidden = false;
      document.title = `dancegen — ${Math.floor(p * 100)} %`;
      break;
    }
    case 'done':
      $('progress-box').hidden = true;
      document.title = `dancegen — ${danceTitle(job)}`;
      if (!viewer) showDone(job);
      break;
    case 'failed':
      document.title = 'dancegen — failed';
      failJob(`The dance could not be made: ${job.error || 'the server gave no reason'}.`,
        job.params?.edit ? null : { href: againHref(job.id), text: 'Try again with these settings' });
      status.textContent = 'The dance could not be made.';
      eta.textContent = '';
      break;
    case 'cancelled':
      document.title = 'dancegen — cancelled';
      failJob(job.error ? `This job was cancelled: ${job.error}` : 'This job was cancelled.',
        job.params?.edit ? null : { href: againHref(job.id), text: 'Try again with these settings' });
      status.textContent = 'Cancelled.';
      eta.textContent = '';
      break;
    default:
      status.textContent = `Unknown job state “${job.state}”.`;
  }
}

/** The job's warnings (job.warnings: sentences), one list item each; hidden when none. */
function showWarnings(warnings) {
  const list = $('job-warnings');
  const items = (warnings ?? []).map((w) => {
    const li = document.createElement('li');
    li.textContent = `Note: ${w}.`;
    return li;
  });
  list.replaceChildren(...items);
  list.hidden = items.length === 0;
}

function showFiles(files) {
  const entries = Object.entries(files ?? {});
  $('all-files').hidden = entries.length === 0;
  const list = $('file-list');
  list.replaceChildren();
  for (const [name, url] of entries) {
    const li = document.createElement('li');
    li.append(downloadLinks({ [name]: url }, {}));
    list.append(li);
  }
}

function startViewer(job) {
  $('viewer').hidden = false;
  const ready = viewerReady;
  try {
    viewer = new Viewer($('viewer'), job);
  } catch (e) {
    // No WebGL (switched off, or an old graphics driver): the files can still be downloaded.
    $('viewer').hidden = true;
    $('variations-box').replaceChildren();
    for (const a of $('viewer').querySelectorAll('audio')) a.remove();
    const message = `This browser cannot show the dance in 3D (${e.message}). The files below can still be downloaded.`;
    showNotice(message);
    $('all-files').open = true;
    ready.reject(new Error(message));
    return;
  }
  viewer.onError = (e) => showNotice(e.message);
  const shown = viewer;
  viewer.ready.then(
    () => {
      // Editing goes with one job's own viewer, not with a comparison.
      if (viewer === shown && !comparing) editPanel = new EditPanel(job, viewer, page);
      ready.resolve();
    },
    (e) => {
      showNotice(e.message);
      ready.reject(e);
    },
  );
}

window.addEventListener('popstate', route);
route();
