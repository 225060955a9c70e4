#!/usr/bin/env node
/**
 * Drives the song form of the web app in headless Chromium, with the keyboard and on a phone,
 * and reports what it showed, for the server's Rust test to check:
 *
 *   node form_check.mjs <base_url> <out_dir> <empty_file> <song> <character.glb>
 *
 * Desktop (1280 × 900): tabs to the drop zone, presses Enter, and, when a file chooser opens,
 * gives it <empty_file> (0 bytes); presses Space on the zone again; then submits the form.
 * Phone (375 × 667, touch): reads the drop zone's words and how wide each dance system's name
 * is against the room its select has. Then the character field (desktop): which systems offer
 * it, <empty_file> refused as a character, and <character.glb> sent with <song>, ending at 4 s
 * (the job's params read back). Last, "Try again" from <cancelled_job_id>'s page. Screenshots:
 * <out_dir>/phone.png, character-form.png, again.png. Prints ONE JSON line:
 *
 *   {"desktop": {"focused": id of the element focused after the tabs, "enter": chooser opened,
 *    "space": chooser opened, "name": the chosen file's line, "notice": the message after
 *    submit, "invalid": the field marked invalid},
 *    "phone": {"words": drop zone text, "room": px for the text, "options": [[text, px]]},
 *    "character": {"shownFor": {system: field shown}, "refused": {notice, invalid},
 *                  "params": the params of the job the form made},
 *    "again": the form filled in from <cancelled_job_id> through its page's "Try again" link:
 *             {link: {text, href}, url, notice, system, seed, end, rig, variations,
 *              song: [name, size], songName, character: [name, size]},
 *    "errors": [page errors]}
 *
 * It asserts nothing (the Rust test does) and exits 0, except when the page never shows its
 * form within 60 s: then it exits 1 with the reason on stderr.
 */
import { mkdirSync } from 'node:fs';
import { join } from 'node:path';
import { collectErrors, launchChromium, ownedPage } from './chromium.mjs';

// Generous: every check waits for a chooser that should open, and with the other server tests
// generating dances on both cores, 3 s was once too short for the first one.
const CHOOSER_MS = 15_000;

const [baseArg, outDir, emptyFile, songFile, characterFile, cancelledJob] = process.argv.slice(2);
if (!baseArg || !outDir || !emptyFile || !songFile || !characterFile || !cancelledJob) {
  console.error('usage: node form_check.mjs <base_url> <out_dir> <empty_file> <song> <character.glb> <cancelled_job_id>');
  process.exit(2);
}
const base = baseArg.replace(/\/+$/, '');
mkdirSync(outDir, { recursive: true });
const errors = [];
const result = { desktop: {}, phone: {}, errors };

const browser = await launchChromium();
let exitCode = 0;
try {
  const open = async (page) => {
    collectErrors(page, errors);
    await page.goto(`${base}/`, { waitUntil: 'networkidle0' });
    // The systems are loaded when the select is enabled.
    await page.waitForSelector('#system:not([disabled])', { timeout: 60_000 });
  };
  /** Whether pressing `key` on the focused drop zone opens a file chooser (and the chooser). */
  const chooserOn = async (page, key) => {
    const waiting = page.waitForFileChooser({ timeout: CHOOSER_MS }).catch(() => null);
    await page.keyboard.press(key);
    return waiting;
  };

  const desk = await ownedPage(browser);
  await desk.setViewport({ width: 1280, height: 900 });
  await open(desk);
  // waitForFileChooser turns interception on without waiting for the browser's answer, so the
  // first key press can beat it and the chooser opens unseen (puppeteer issue #6040; CI lost
  // the Enter check that way once). Turn it on here, awaited; it then stays on for the page.
  await desk._client().send('Page.setInterceptFileChooserDialog', { enabled: true });
  // Tab from the page's start until the drop zone has the focus (at most 10 stops).
  for (let i = 0; i < 10; i++) {
    await desk.keyboard.press('Tab');
    if (await desk.evaluate(() => document.activeElement?.id === 'drop-zone')) break;
  }
  result.desktop.focused = await desk.evaluate(() => document.activeElement?.id ?? null);
  const chooser = await chooserOn(desk, 'Enter');
  result.desktop.enter = chooser !== null;
  if (chooser) await chooser.accept([emptyFile]);
  await desk.focus('#drop-zone');
  const again = await chooserOn(desk, 'Space');
  result.desktop.space = again !== null;
  if (again) await again.cancel();
  result.desktop.name = await desk.$eval('#song-name', (e) => (e.hidden ? null : e.textContent));
  await desk.click('#submit');
  await new Promise((r) => setTimeout(r, 300));
  result.desktop.notice = await desk.$eval('#notice', (e) => (e.hidden ? null : e.textContent));
  result.desktop.invalid = await desk.evaluate(() => document.querySelector('[aria-invalid="true"]')?.id ?? null);

  const phone = await ownedPage(browser);
  await phone.emulate({
    viewport: { width: 375, height: 667, deviceScaleFactor: 2, isMobile: true, hasTouch: true },
    userAgent: 'Mozilla/5.0 (Linux; Android 14) AppleWebKit/537.36 (KHTML, like Gecko) Chrome/130.0 Mobile Safari/537.36',
  });
  await open(phone);
  result.phone = await phone.evaluate(() => {
    const zone = document.querySelector('#drop-zone label');
    const select = document.getElementById('system');
    const style = getComputedStyle(select);
    const ctx = document.createElement('canvas').getContext('2d');
    ctx.font = `${style.fontWeight} ${style.fontSize} ${style.fontFamily}`;
    // The text's room: the select's inner width less its padding and the drop-down arrow.
    const arrow = 24;
    const room = select.clientWidth - parseFloat(style.paddingLeft) - parseFloat(style.paddingRight) - arrow;
    return {
      words: zone.textContent.replace(/\s+/g, ' ').trim(),
      room,
      options: [...select.options].map((o) => [o.textContent, ctx.measureText(o.textContent).width]),
    };
  });
  await phone.screenshot({ path: join(outDir, 'phone.png'), fullPage: true });

  // The character flow: the field offered for one dancer only; a file that is not a .glb or
  // .vrm refused in the page, naming the field; the character sent with a song makes a job
  // whose params name it.
  const page = await ownedPage(browser);
  await page.setViewport({ width: 1280, height: 900 });
  await open(page);
  const shownFor = {};
  for (const system of ['solo', 'duet', 'group', 'holistic']) {
    await page.select('#system', system);
    shownFor[system] = await page.$eval('#character-field', (e) => !e.hidden);
  }
  result.character = { shownFor };
  await page.select('#system', 'solo');
  await (await page.$('#song')).uploadFile(songFile);
  await page.$eval('#end', (e) => { e.value = '4'; });
  const character = await page.$('#character');
  await character.uploadFile(emptyFile);
  await page.click('#submit');
  await new Promise((r) => setTimeout(r, 300));
  result.character.refused = {
    notice: await page.$eval('#notice', (e) => (e.hidden ? null : e.textContent)),
    invalid: await page.evaluate(() => document.querySelector('[aria-invalid="true"]')?.id ?? null),
  };
  await character.uploadFile(characterFile);
  await page.screenshot({ path: join(outDir, 'character-form.png') });
  await page.click('#submit');
  // The job's page, or the refusal shown in the notice.
  await page.waitForFunction(() => new URLSearchParams(location.search).has('job')
    || (!document.getElementById('notice').hidden && document.getElementById('submit').textContent !== 'Uploading…'), { timeout: 60_000 });
  result.character.params = await page.evaluate(async () => {
    const id = new URLSearchParams(location.search).get('job');
    if (!id) return { refused: document.getElementById('notice').textContent };
    return (await (await fetch(`api/jobs/${encodeURIComponent(id)}`)).json()).params;
  });

  // "Try again" on a cancelled job: its page links to the form filled in from it, and the
  // form holds its settings and its files.
  const retry = await ownedPage(browser);
  await retry.setViewport({ width: 1280, height: 900 });
  collectErrors(retry, errors);
  await retry.goto(`${base}/?job=${encodeURIComponent(cancelledJob)}`, { waitUntil: 'networkidle0' });
  await retry.waitForSelector('#notice a', { timeout: 60_000 });
  const link = await retry.$eval('#notice a', (a) => ({ text: a.textContent, href: a.getAttribute('href') }));
  await retry.click('#notice a');
  await retry.waitForFunction(() => document.getElementById('notice').dataset.kind === 'info'
    || /could not be filled/.test(document.getElementById('notice').textContent), { timeout: 60_000 });
  result.again = await retry.evaluate(() => {
    const v = (id) => document.getElementById(id).value;
    const file = (id) => {
      const f = document.getElementById(id).files[0];
      return f ? [f.name, f.size] : null;
    };
    return {
      url: location.search,
      notice: document.getElementById('notice').textContent,
      system: v('system'), seed: v('seed'), end: v('end'), rig: v('rig'), variations: v('variations'),
      song: file('song'), songName: document.getElementById('song-name').textContent,
      character: file('character'),
    };
  });
  result.again.link = link;
  await retry.screenshot({ path: join(outDir, 'again.png') });
} catch (e) {
  console.error(`form_check: ${e.message}`);
  exitCode = 1;
} finally {
  await browser.close().catch(() => {});
}
if (exitCode === 0) process.stdout.write(`${JSON.stringify(result)}\n`);
process.exit(exitCode);
