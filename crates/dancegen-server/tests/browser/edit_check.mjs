#!/usr/bin/env node
/**
 * Drives the editing flow of the web app in headless Chromium and reports what happened, for
 * the server's Rust test to check:
 *
 *   node edit_check.mjs <base_url> <job_id> <out_dir>
 *
 * Opens <base_url>/?job=<job_id>, marks 1 s of the dance with "Mark start here" (seeking the
 * song there), then drags along the strip under the timeline from 20 % to 40 % of it (2-4 s
 * of a 10 s dance), keeps the arms, presses
 * "Regenerate this part", follows the page to the new version until its viewer is ready,
 * reads the versions list, then opens "Compare side by side" with the first version and reads
 * the two dances' titles and download links. Screenshots: <out_dir>/selection.png,
 * edited.png, compare.png. Prints ONE JSON line:
 *
 *   {"edited": new job id, "marked": the from field after the mark, "dragged": [from, to] after
 *    the drag, "selection": {"hidden", "left", "width"}, "continueShown",
 *    "versions": [text of each item], "compare": {"url", "titles", "downloads": [count each],
 *    "figures"}, "requests": [...], "errors": [...]}
 *
 * It asserts nothing (the Rust test does) and exits 0, except when a step never finishes
 * within its time: then it exits 1 with the reason and the page's errors on stderr.
 */
import { mkdirSync } from 'node:fs';
import { join } from 'node:path';
import puppeteer from 'puppeteer-core';
import { ownedPage } from './chromium.mjs';

const CHROMIUM = process.env.CHROMIUM ?? '/usr/bin/chromium';
const STEP_TIMEOUT_MS = 60_000;
/** The new version is a generation: the queue, the model, the song. */
const EDIT_TIMEOUT_MS = 300_000;

const [baseArg, jobId, outDir] = process.argv.slice(2);
if (!baseArg || !jobId || !outDir) {
  console.error('usage: node edit_check.mjs <base_url> <job_id> <out_dir>');
  process.exit(2);
}
const base = baseArg.replace(/\/+$/, '');
mkdirSync(outDir, { recursive: true });

const requests = [];
const errors = [];

const browser = await puppeteer.launch({
  executablePath: CHROMIUM,
  headless: true,
  args: ['--no-sandbox', '--autoplay-policy=no-user-gesture-required', '--enable-unsafe-swiftshader', '--use-angle=swiftshader'],
});

let exitCode = 0;
try {
  const page = await ownedPage(browser);
  await page.setViewport({ width: 1280, height: 900 });
  page.on('request', (r) => requests.push(r.url()));
  page.on('pageerror', (e) => errors.push(`pageerror: ${e?.message ?? e}`));
  page.on('console', (m) => { if (m.type() === 'error') errors.push(`console: ${m.text()}`); });
  page.on('response', (r) => { if (r.status() >= 400) errors.push(`HTTP ${r.status()} ${r.url()}`); });

  /** Waits for the open job's viewer and its edit box (rejects in the page's words). */
  const ready = (ms) => page.waitForFunction(() => window.__viewer !== undefined, { timeout: ms })
    .then(() => page.evaluate(async () => { await window.__viewer.ready; await window.__viewer.edited(); }));
  const frames = () => page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  const shot = async (name) => { await frames(); await (await page.$('#job-view')).screenshot({ path: join(outDir, name) }); };
  const step = async (what, ms, fn) => {
    let timer;
    const timeout = new Promise((_, reject) => { timer = setTimeout(() => reject(new Error(`no answer within ${ms / 1000} s`)), ms); });
    try {
      return await Promise.race([fn(), timeout]);
    } catch (e) {
      const notice = await page.$eval('#notice', (n) => (n.hidden ? '' : n.textContent)).catch(() => '');
      throw new Error(`${what}: ${String(e.message).split('\n')[0]}${notice ? ` (the page says: ${notice})` : ''}`);
    } finally {
      clearTimeout(timer);
    }
  };

  const result = { requests, errors };
  try {
    await step('open the job', STEP_TIMEOUT_MS, async () => {
      await page.goto(`${base}/?job=${encodeURIComponent(jobId)}`, { waitUntil: 'domcontentloaded' });
      await ready(STEP_TIMEOUT_MS);
    });
    await step('mark, then drag 2-4 s', STEP_TIMEOUT_MS, async () => {
      await page.evaluate(() => window.__viewer.seek(1));
      await page.click('#mark-from');
      result.marked = await page.$eval('#edit-from', (i) => i.value);
      // Clicking the mark button scrolled the page down to it; the strip is at the top of
      // the viewer, so back up to it first (as a user would).
      const r = await page.$eval('#range-track', (t) => {
        t.scrollIntoView({ block: 'center' });
        const b = t.getBoundingClientRect();
        return { x: b.left, y: b.top + b.height / 2, w: b.width };
      });
      await page.mouse.move(r.x + 0.2 * r.w, r.y);
      await page.mouse.down();
      await page.mouse.move(r.x + 0.3 * r.w, r.y, { steps: 4 });
      await page.mouse.move(r.x + 0.4 * r.w, r.y, { steps: 4 });
      await page.mouse.up();
      result.dragged = await page.evaluate(() => [document.getElementById('edit-from').value, document.getElementById('edit-to').value]);
      await page.select('#edit-keep', 'arms');
      result.selection = await page.$eval('#selection', (b) => ({ hidden: b.hidden, left: b.style.left, width: b.style.width }));
      result.continueShown = await page.$eval('#continue-fields', (b) => !b.hidden);
      await shot('selection.png');
    });
    await step('regenerate and open the new version', EDIT_TIMEOUT_MS, async () => {
      await page.click('#regenerate');
      await page.waitForFunction((old) => {
        const id = new URLSearchParams(location.search).get('job');
        return id && id !== old;
      }, { timeout: EDIT_TIMEOUT_MS }, jobId);
      result.edited = await page.evaluate(() => new URLSearchParams(location.search).get('job'));
      await ready(EDIT_TIMEOUT_MS);
      result.versions = await page.$$eval('#version-list li', (items) => items.map((li) => li.textContent));
      result.versionsShown = await page.$eval('#versions-box', (b) => !b.hidden);
      await shot('edited.png');
    });
    await step('compare side by side', STEP_TIMEOUT_MS, async () => {
      await page.click(`#version-list li[data-job="${jobId}"] .compare-version`);
      await page.waitForFunction(() => new URLSearchParams(location.search).has('compare'), { timeout: STEP_TIMEOUT_MS });
      await ready(STEP_TIMEOUT_MS);
      result.compare = await page.evaluate(() => ({
        url: location.search,
        figures: document.querySelectorAll('#variations-box figure').length,
        titles: [...document.querySelectorAll('#variations-box figure .title')].map((t) => t.textContent),
        downloads: [...document.querySelectorAll('#variations-box figure')].map((f) => f.querySelectorAll('.downloads a').length),
        editBoxShown: !document.getElementById('edit-box').hidden,
      }));
      await shot('compare.png');
    });
  } catch (e) {
    console.error(`edit_check: ${e.message}`);
    console.error(`edit_check: page errors: ${JSON.stringify(errors, null, 2)}`);
    exitCode = 1;
  }
  if (exitCode === 0) process.stdout.write(`${JSON.stringify(result)}\n`);
} finally {
  await browser.close().catch(() => {});
}
process.exit(exitCode);
