#!/usr/bin/env node
/**
 * Drives the web viewer of one finished job in headless Chromium and reports what it shows,
 * for the server's Rust test to check against the job's .npy:
 *
 *   node viewer_check.mjs <base_url> <job_id> <out_dir>
 *
 * Opens <base_url>/?job=<job_id>, awaits `window.__viewer.ready`, seeks the song to 1, 2 and
 * 5 s and reads every variation's joint positions, screenshots the viewer at 1 s and 5 s
 * (<out_dir>/shot_1.png, shot_5.png; follow_5.png as the page opened), plays for about a second, and prints ONE JSON line:
 *
 *   {"joints": {"1": [per variation: [dancer][24][x,y,z]], "2": ..., "5": ...},
 *    "seeked": {"1": {"audio": s, "dance": s}, ...},
 *    "play": {"t0": s, "t1": s, "moved": max |joint change| in metres},
 *    "timeline": {shown, beats, peaks, firstBeat, lastBeat, duration, inked (painted pixels)},
 *    "follow": {"1": camera, "5": camera} as the page opened (before any view is chosen),
 *    "views": {front: camera, closeupShown, closeup: camera (holistic)}, where camera is
 *              {view, distance to the head, headInView, face, headSpheres, following,
 *               jointsInView, joints (of the first variation's dancers),
 *               target: [x,y,z], centroid: the dancers' root centroid on the floor [x,0,z]},
 *    "figures": [per variation at 1 s: {heads: [[x,y,z]], shadows: [{at, radius, opacity}],
 *                pelvis: [[x,y,z]], lowest: [y], legend: [text]}],
 *    "downloads": {"variations": [per variation: [{text, href, download}]], "all": {hidden, href}},
 *    "phone": {scrolled, height, canvases: [[top, bottom] in the page], play: {top, bottom, onTop},
 *              scrub: {…}} at 375 × 667 scrolled to the end (screenshot <out_dir>/phone.png),
 *    "requests": [every URL the page asked for], "errors": [page errors, console errors, HTTP ≥ 400]}
 *
 * It asserts nothing (the Rust test does) and exits 0, except when the page never becomes
 * ready within 60 s: then it exits 1 with the reason and the page's errors on stderr.
 */
import { mkdirSync } from 'node:fs';
import { join } from 'node:path';
import puppeteer from 'puppeteer-core';
import { ownedPage } from './chromium.mjs';

const CHROMIUM = process.env.CHROMIUM ?? '/usr/bin/chromium';
const READY_TIMEOUT_MS = 60_000;
const SEEK_TIMES = [1, 2, 5];
const SHOT_TIMES = [1, 5];
const PLAY_MS = 1000;

const [baseArg, jobId, outDir] = process.argv.slice(2);
if (!baseArg || !jobId || !outDir) {
  console.error('usage: node viewer_check.mjs <base_url> <job_id> <out_dir>');
  process.exit(2);
}
const base = baseArg.replace(/\/+$/, '');
mkdirSync(outDir, { recursive: true });

const requests = [];
const errors = [];

/** Rejects after `ms` with `what`, so no step can hang the Rust test. */
function within(ms, what, promise) {
  let timer;
  const timeout = new Promise((_, reject) => {
    timer = setTimeout(() => reject(new Error(`${what} (no answer within ${ms / 1000} s)`)), ms);
  });
  return Promise.race([promise, timeout]).finally(() => clearTimeout(timer));
}

const browser = await puppeteer.launch({
  executablePath: CHROMIUM,
  headless: true,
  args: [
    '--no-sandbox',
    '--autoplay-policy=no-user-gesture-required',
    '--enable-unsafe-swiftshader',
    '--use-angle=swiftshader',
  ],
});

let exitCode = 0;
try {
  const page = await ownedPage(browser);
  await page.setViewport({ width: 1280, height: 800 });
  page.on('request', (r) => requests.push(r.url()));
  page.on('pageerror', (e) => errors.push(`pageerror: ${e?.message ?? e}`));
  page.on('console', (m) => {
    if (m.type() === 'error') errors.push(`console: ${m.text()}`);
  });
  page.on('response', (r) => {
    if (r.status() >= 400) errors.push(`HTTP ${r.status()} ${r.url()}`);
  });

  const url = `${base}/?job=${encodeURIComponent(jobId)}`;
  const notReady = `the viewer at ${url} did not become ready`;
  try {
    await within(READY_TIMEOUT_MS, notReady, (async () => {
      await page.goto(url, { waitUntil: 'domcontentloaded', timeout: READY_TIMEOUT_MS });
      await page.waitForFunction(() => window.__viewer !== undefined, { timeout: READY_TIMEOUT_MS });
      await page.evaluate(() => window.__viewer.ready);
    })());
  } catch (e) {
    // What the page shows the user says most about why (job failed, file missing, ...).
    const notice = await page.$eval('#notice', (n) => (n.hidden ? '' : n.textContent)).catch(() => '');
    const status = await page.$eval('#job-status', (n) => (n.closest('[hidden]') ? '' : n.textContent)).catch(() => '');
    // The page's own rejection (job failed, file missing) without puppeteer's stack lines.
    const reason = String(e.message).split('\n')[0];
    console.error(`viewer_check: ${reason.startsWith(notReady) ? reason : `${notReady}: ${reason}`}`);
    if (notice) console.error(`viewer_check: the page says: ${notice}`);
    if (status && !notice) console.error(`viewer_check: the job's status on the page: ${status}`);
    console.error(`viewer_check: page errors: ${JSON.stringify(errors, null, 2)}`);
    exitCode = 1;
  }

  if (exitCode === 0) {
    const result = { joints: {}, seeked: {}, play: null, requests, errors };
    /** Seeks to `t` (song seconds) and returns {seeked, joints: per variation}. */
    const seekAndRead = (t) => within(30_000, `seek to ${t} s`, page.evaluate(async (t) => {
      const v = window.__viewer;
      const seeked = await v.seek(t);
      const joints = [];
      for (let i = 0; i < v.count(); i++) joints.push(v.joints(i));
      return { seeked, joints };
    }, t));
    const step = async (what, fn) => {
      try { await fn(); } catch (e) { errors.push(`viewer_check: ${what}: ${e.message}`); }
    };

    for (const t of SEEK_TIMES) {
      await step(`seek to ${t} s`, async () => {
        const r = await seekAndRead(t);
        result.joints[t] = r.joints;
        result.seeked[t] = r.seeked;
      });
    }
    // What is drawn around the joints, at the first seek time: heads, contact shadows, legend.
    await step('figures', async () => {
      result.figures = await within(30_000, 'read the figures', page.evaluate(async (t) => {
        const v = window.__viewer;
        await v.seek(t);
        return Array.from({ length: v.count() }, (_, i) => v.figures(i));
      }, SEEK_TIMES[0]));
      result.timeline = await page.evaluate(() => window.__viewer.timeline());
    });
    // The camera as the page opens: following the dancers (read at 1 s and 5 s, each after the
    // frame that seek drew).
    await step('follow', async () => {
      result.follow = {};
      for (const t of [1, 5]) {
        await seekAndRead(t);
        await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
        result.follow[t] = await page.evaluate(() => window.__viewer.camera());
      }
      await (await page.$('#viewer')).screenshot({ path: join(outDir, 'follow_5.png') });
      // Back to the first seek time, where the views below were always read.
      await seekAndRead(1);
    });
    // The camera presets: Front, and the holistic close-up where it is offered.
    await step('views', async () => {
      const v = {};
      await page.click('.view[data-view="front"]');
      v.front = await page.evaluate(() => window.__viewer.camera());
      v.closeupShown = await page.$eval('.view[data-view="closeup"]', (b) => !b.hidden);
      if (v.closeupShown) {
        await page.click('.view[data-view="closeup"]');
        await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
        v.closeup = await page.evaluate(() => window.__viewer.camera());
        await (await page.$('#viewer')).screenshot({ path: join(outDir, 'closeup.png') });
        await page.click('.view[data-view="front"]');
      }
      result.views = v;
    });
    const viewerBox = await page.$('#viewer');
    for (const t of SHOT_TIMES) {
      await step(`screenshot at ${t} s`, async () => {
        await seekAndRead(t);
        // Two animation frames, so the composited page holds the frame rendered for `t`.
        await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
        await viewerBox.screenshot({ path: join(outDir, `shot_${t}.png`) });
      });
    }
    await step('play', async () => {
      result.play = await within(30_000, 'play for 1 s', page.evaluate(async (ms) => {
        const v = window.__viewer;
        const all = () => Array.from({ length: v.count() }, (_, i) => v.joints(i));
        const before = all();
        const t0 = v.audio().currentTime;
        await v.play();
        await new Promise((r) => setTimeout(r, ms));
        const t1 = v.audio().currentTime;
        const after = all();
        v.audio().pause();
        let moved = 0;
        before.forEach((variation, i) => variation.forEach((dancer, d) => dancer.forEach((p, j) => p.forEach((x, k) => {
          moved = Math.max(moved, Math.abs(x - after[i][d][j][k]));
        }))));
        return { t0, t1, moved };
      }, PLAY_MS));
    });
    // The playback controls: every speed, Loop (played over the dance's end it starts again),
    // full screen. The dance of the test jobs starts at the song's 0 s.
    await step('controls', async () => {
      const c = {};
      c.speeds = await page.$$eval('.speed', (bs) => bs.map((b) => Number(b.dataset.rate)));
      await page.click('.speed[data-rate="2"]');
      c.rate = await page.evaluate(() => window.__viewer.audio().playbackRate);
      await page.click('.speed[data-rate="1"]');
      await page.click('#loop');
      c.loop = await within(30_000, 'loop', page.evaluate(async () => {
        const v = window.__viewer;
        const a = v.audio();
        const end = Number(document.getElementById('scrub').max);
        await v.seek(end - 0.4);
        await v.play();
        await new Promise((r) => setTimeout(r, 1200));
        const after = { time: a.currentTime, paused: a.paused, end };
        a.pause();
        return after;
      }));
      await page.click('#loop');
      c.fullscreenEnabled = await page.evaluate(() => document.fullscreenEnabled);
      await page.click('#fullscreen');
      await new Promise((r) => setTimeout(r, 300));
      c.fullscreen = await page.evaluate(() => document.fullscreenElement?.id ?? null);
      await page.evaluate(() => document.exitFullscreen?.().catch(() => {}));
      result.controls = c;
    });
    await step('downloads', async () => {
      result.downloads = await page.evaluate(() => ({
        variations: [...document.querySelectorAll('#variations-box figure')].map((f) =>
          [...f.querySelectorAll('.downloads a')].map((a) => ({ text: a.textContent, href: a.getAttribute('href'), download: a.getAttribute('download') }))),
        all: { hidden: document.getElementById('download-all-box').hidden, href: document.getElementById('download-all').getAttribute('href') },
      }));
    });
    // On a phone (375 × 667): scrolled to the end of the page, past the stacked variations,
    // Play and the timeline are still on the screen and nothing covers them.
    await step('phone', async () => {
      await page.setViewport({ width: 375, height: 667, isMobile: true, hasTouch: true });
      await new Promise((r) => setTimeout(r, 300));
      await page.evaluate(() => window.scrollTo(0, document.documentElement.scrollHeight));
      await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
      result.phone = await page.evaluate(() => {
        const reach = (id) => {
          const r = document.getElementById(id).getBoundingClientRect();
          const top = document.elementFromPoint(r.left + r.width / 2, r.top + r.height / 2);
          return { top: r.top, bottom: r.bottom, onTop: Boolean(top?.closest(`#${id}`)) };
        };
        return {
          scrolled: window.scrollY,
          height: window.innerHeight,
          canvases: [...document.querySelectorAll('#variations-box .canvas-box')].map((c) => {
            const r = c.getBoundingClientRect();
            return [r.top + window.scrollY, r.bottom + window.scrollY];
          }),
          play: reach('play'),
          scrub: reach('scrub'),
        };
      });
      await page.screenshot({ path: join(outDir, 'phone.png') });
    });
    process.stdout.write(`${JSON.stringify(result)}\n`);
  }
} finally {
  await browser.close().catch(() => {});
}
process.exit(exitCode);
