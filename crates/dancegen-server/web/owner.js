/**
 * This browser's owner secret: the server returns it when the first dance is made, and every
 * later request that changes or lists dances sends it (`Authorization: Bearer SECRET`). All
 * of this browser's dances share it, so "My dances" lists them, and only this browser (or the
 * server's administrator) can rename, edit or delete them. A link to a dance needs no secret
 * to be watched.
 */

const KEY = 'dancegen-owner-secret';

function stored() {
  try {
    return window.localStorage.getItem(KEY);
  } catch {
    return null; // storage disabled: the page still works, each dance gets its own secret
  }
}

/** `fetch` options with this browser's secret added to `init`'s headers (when it has one). */
export function owned(init = {}) {
  const secret = stored();
  if (!secret) return init;
  return { ...init, headers: { ...(init.headers ?? {}), Authorization: `Bearer ${secret}` } };
}

/** Keeps the secret a job's creation returned (`{"id", "owner"}`). */
export function rememberOwner(reply) {
  if (typeof reply?.owner !== 'string') return;
  try {
    window.localStorage.setItem(KEY, reply.owner);
  } catch {
    /* storage disabled */
  }
}
