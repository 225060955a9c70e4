#!/usr/bin/env node
/**
 * Drives "My dances" of the web app in headless Chromium and reports what happened, for the
 * server's Rust test to check:
 *
 *   node library_check.mjs <base_url> <out_dir> [stranger]
 *
 * The page acts as the browser that made the dances (`ownedPage`: the owner secret in
 * `DANCEGEN_OWNER_SECRET`), so its library lists them. With `stranger` it has no secret: the
 * page is opened, its library request answered, the items (none expected) read and printed,
 * and nothing else is done.
 * Opens <base_url>/, waits for the library's items and reads them (job id, title, the line
 * under it, the buttons, whether the picture loaded), screenshots the page
 * (<out_dir>/library.png, and at phone size library_phone.png), renames the first dance
 * through the page's prompt ("Salsa night") and reads its title again, deletes the last one
 * (accepting the confirmation) and reads the ids left, then opens ?job=<the deleted id> and
 * reads the notice and its link. Prints ONE JSON line:
 *
 *   {"items": [{id, title, meta, buttons: [text], picture}], "renamed": title,
 *    "dialogs": [{type, message}], "left": [ids], "unknown": {notice, link},
 *    "requests": [...], "errors": [...]}
 *
 * It asserts nothing (the Rust test does) and exits 0, except when a step never finishes
 * within its time: then it exits 1 with the reason and the page's errors on stderr.
 */
import { mkdirSync } from 'node:fs';
import { join } from 'node:path';
import { collectErrors, launchChromium, ownedPage } from './chromium.mjs';

const STEP_TIMEOUT_MS = 30_000;

const [baseArg, outDir, mode] = process.argv.slice(2);
if (!baseArg || !outDir) {
  console.error('usage: node library_check.mjs <base_url> <out_dir>');
  process.exit(2);
}
const base = baseArg.replace(/\/+$/, '');
mkdirSync(outDir, { recursive: true });

const requests = [];
const errors = [];
const dialogs = [];

const browser = await launchChromium();

let exitCode = 0;
try {
  const page = mode === 'stranger' ? await browser.newPage() : await ownedPage(browser);
  await page.setViewport({ width: 1100, height: 900 });
  page.on('request', (r) => requests.push(r.url()));
  // The deleted dance's page asks for it and is answered 404, as it should be: from then on
  // the browser's "Failed to load resource: … 404" lines are expected.
  let deletedOpen = false;
  collectErrors(page, errors, (text) => deletedOpen && text.includes('status of 404'));
  page.on('response', (r) => { if (r.status() >= 400 && !r.url().includes('/api/jobs/')) errors.push(`HTTP ${r.status()} ${r.url()}`); });
  page.on('dialog', async (d) => {
    dialogs.push({ type: d.type(), message: d.message() });
    if (d.type() === 'prompt') await d.accept('Salsa night');
    else await d.accept();
  });
  const items = () => page.$$eval('#library-list li', (lis) => lis.map((li) => ({
    id: li.dataset.job,
    title: li.querySelector('.title')?.textContent,
    meta: li.querySelector('.meta')?.textContent,
    buttons: [...li.querySelectorAll('.actions button')].map((b) => b.textContent),
    picture: (() => { const i = li.querySelector('.thumb img'); return i ? i.complete && i.naturalWidth > 0 : false; })(),
  })));
  const result = { requests, errors, dialogs };
  try {
    await page.goto(`${base}/`, { waitUntil: 'networkidle0', timeout: STEP_TIMEOUT_MS });
    if (mode === 'stranger') {
      result.items = await items();
      console.log(JSON.stringify(result));
      await browser.close();
      process.exit(0);
    }
    await page.waitForSelector('#library-list li', { timeout: STEP_TIMEOUT_MS });
    await page.waitForFunction(() => [...document.querySelectorAll('#library-list img')].every((i) => i.complete), { timeout: STEP_TIMEOUT_MS });
    result.items = await items();
    await (await page.$('#library')).screenshot({ path: join(outDir, 'library.png') });

    const first = result.items[0].id;
    await page.click(`#library-list li[data-job="${first}"] .rename`);
    await page.waitForFunction((id) => document.querySelector(`#library-list li[data-job="${id}"] .title`)?.textContent === 'Salsa night', { timeout: STEP_TIMEOUT_MS }, first);
    result.renamed = await page.$eval(`#library-list li[data-job="${first}"] .title`, (t) => t.textContent);

    const last = result.items[result.items.length - 1].id;
    await page.click(`#library-list li[data-job="${last}"] .delete`);
    await page.waitForFunction((id) => !document.querySelector(`#library-list li[data-job="${id}"]`), { timeout: STEP_TIMEOUT_MS }, last);
    result.left = (await items()).map((i) => i.id);

    await page.setViewport({ width: 390, height: 844, isMobile: true, hasTouch: true });
    await (await page.$('#library')).screenshot({ path: join(outDir, 'library_phone.png') });

    deletedOpen = true;
    await page.goto(`${base}/?job=${encodeURIComponent(last)}`, { waitUntil: 'domcontentloaded' });
    await page.waitForFunction(() => !document.getElementById('notice').hidden, { timeout: STEP_TIMEOUT_MS });
    result.unknown = await page.$eval('#notice', (n) => ({ notice: n.textContent, link: n.querySelector('a')?.getAttribute('href') ?? null }));
  } catch (e) {
    console.error(`library_check: ${String(e.message).split('\n')[0]}`);
    console.error(`library_check: page errors: ${JSON.stringify(errors, null, 2)}`);
    exitCode = 1;
  }
  if (exitCode === 0) process.stdout.write(`${JSON.stringify(result)}\n`);
} finally {
  await browser.close().catch(() => {});
}
process.exit(exitCode);
