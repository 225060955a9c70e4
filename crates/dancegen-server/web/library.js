/**
 * "My dances": the dances this browser made (its owner secret, `owner.js`), newest first,
 * under the form. Each shows its
 * picture, its name (or its song's), system, seed, state and date, with Open, Rename, Delete
 * (after a confirmation) and, for a finished dance, "Again with another seed" — or "Try
 * again" for one that failed or was cancelled, with the same settings and song.
 */

import { owned, rememberOwner } from './owner.js';

const SYSTEM_WORDS = { solo: 'Solo', duet: 'Duet', group: 'Group', holistic: 'Body, hands and face' };
export const STATE_WORDS = { queued: 'waiting', running: 'being made', done: 'done', failed: 'failed', cancelled: 'cancelled' };

/** The page that reopens the form filled in from job `id` ("Try again"). */
export function againHref(id) {
  return `?again=${encodeURIComponent(id)}`;
}

/** A dance's title in the library: its name, else its song's. */
export function danceTitle(job) {
  return job.name || job.params?.song_title || 'Untitled dance';
}

function when(seconds) {
  const d = new Date(seconds * 1000);
  return d.toLocaleString(undefined, { dateStyle: 'medium', timeStyle: 'short' });
}

/** Answer in words for a failed request (the server's `{error}`, or the status). */
async function failure(res, what) {
  try {
    const body = await res.json();
    if (typeof body?.error === 'string') return `${what}: ${body.error}`;
  } catch { /* not JSON */ }
  return `${what}: the server answered ${res.status}.`;
}

export class Library {
  /** `root` is the #library section; `notify(text)` shows words to the user. */
  constructor(root, notify) {
    this.root = root;
    this.list = root.querySelector('#library-list');
    this.empty = root.querySelector('#library-empty');
    this.notify = notify;
  }

  async refresh() {
    let jobs;
    try {
      const res = await fetch('api/jobs', owned());
      if (!res.ok) throw new Error(await failure(res, 'Listing your dances'));
      jobs = (await res.json()).jobs ?? [];
    } catch (e) {
      this.notify(e.message);
      return;
    }
    this.root.hidden = false;
    this.empty.hidden = jobs.length > 0;
    this.list.replaceChildren(...jobs.map((j) => this.item(j)));
  }

  item(job) {
    const li = document.createElement('li');
    li.className = 'dance';
    li.dataset.job = job.id;
    const href = `?job=${encodeURIComponent(job.id)}`;
    const thumb = document.createElement('a');
    thumb.className = 'thumb';
    thumb.href = href;
    if (job.thumbnail) {
      const img = document.createElement('img');
      img.src = job.thumbnail;
      img.alt = `A moment of ${danceTitle(job)}`;
      img.loading = 'lazy';
      thumb.append(img);
    } else {
      thumb.textContent = STATE_WORDS[job.state] ?? job.state;
    }
    const about = document.createElement('div');
    about.className = 'about';
    const title = document.createElement('a');
    title.className = 'title';
    title.href = href;
    title.textContent = danceTitle(job);
    const meta = document.createElement('span');
    meta.className = 'meta';
    const edit = job.params?.edit ? ' · an edited version' : '';
    meta.textContent = `${SYSTEM_WORDS[job.system] ?? job.system} · seed ${job.params?.seed ?? 0} · ${STATE_WORDS[job.state] ?? job.state}${edit} · ${when(job.created)}`;
    const actions = document.createElement('span');
    actions.className = 'actions';
    const button = (cls, text, fn) => {
      const b = document.createElement('button');
      b.type = 'button';
      b.className = `secondary ${cls}`;
      b.textContent = text;
      b.addEventListener('click', () => fn(b));
      actions.append(b);
    };
    button('open', 'Open', () => { location.href = href; });
    button('rename', 'Rename', () => this.rename(job));
    button('delete', 'Delete', () => this.remove(job));
    if (!job.params?.edit && job.state === 'done') {
      button('again', 'Again with another seed', () => this.again(job, this.nextSeed(job)));
    } else if (!job.params?.edit && (job.state === 'failed' || job.state === 'cancelled')) {
      // The form filled in with its settings and files, to change what made it fail.
      button('again', 'Try again', () => { location.href = againHref(job.id); });
    }
    about.append(title, meta, actions);
    li.append(thumb, about);
    return li;
  }

  /** The first seed none of the job's variations used. */
  nextSeed(job) {
    return (Number(job.params?.seed) || 0) + Math.max(1, Number(job.params?.variations) || 1);
  }

  async rename(job) {
    const name = window.prompt('Name this dance (empty: the song\'s name):', job.name ?? '');
    if (name === null) return;
    const res = await fetch(`api/jobs/${encodeURIComponent(job.id)}`, owned({
      method: 'PATCH',
      headers: { 'Content-Type': 'application/json' },
      body: JSON.stringify({ name }),
    }));
    if (!res.ok) this.notify(await failure(res, 'Renaming'));
    await this.refresh();
  }

  async remove(job) {
    if (!window.confirm(`Delete "${danceTitle(job)}" and all its files? This cannot be undone.`)) return;
    const res = await fetch(`api/jobs/${encodeURIComponent(job.id)}`, owned({ method: 'DELETE' }));
    if (!res.ok) this.notify(await failure(res, 'Deleting'));
    await this.refresh();
  }

  /** A new job from this one (its song and settings; `seed` when given); opens it. */
  async again(job, seed) {
    const res = await fetch(`api/jobs/${encodeURIComponent(job.id)}/again`, owned({
      method: 'POST',
      headers: { 'Content-Type': 'application/json' },
      body: JSON.stringify(seed === undefined ? {} : { seed }),
    }));
    if (!res.ok) {
      this.notify(await failure(res, 'Making it again'));
      return;
    }
    const reply = await res.json();
    rememberOwner(reply);
    location.href = `?job=${encodeURIComponent(reply.id)}`;
  }
}
