/**
 * What the browser checks share: Debian's Chromium started headless through puppeteer-core
 * (software WebGL, no sandbox: the tests run as root in CI), and a page's errors collected
 * (uncaught exceptions and console errors) for the Rust test to assert on.
 */
import puppeteer from 'puppeteer-core';

const CHROMIUM = process.env.CHROMIUM ?? '/usr/bin/chromium';

/** Headless Chromium; `extraArgs` are added to the common flags. */
export function launchChromium(extraArgs = []) {
  return puppeteer.launch({
    executablePath: CHROMIUM,
    headless: true,
    args: ['--no-sandbox', '--enable-unsafe-swiftshader', '--use-angle=swiftshader', ...extraArgs],
  });
}

/** Pushes `page`'s uncaught exceptions and console errors onto `errors` (unless `ignore(text)`). */
export function collectErrors(page, errors, ignore = () => false) {
  page.on('pageerror', (e) => errors.push(`page error: ${e?.message ?? e}`));
  page.on('console', (m) => {
    if (m.type() === 'error' && !ignore(m.text())) errors.push(`console: ${m.text()}`);
  });
}

/**
 * A new page acting as the browser that made the test's jobs: the owner secret the Rust test's
 * client holds (`DANCEGEN_OWNER_SECRET`) is put in local storage, where the page keeps it.
 * Without the variable, a plain new page.
 */
export async function ownedPage(browser) {
  const page = await browser.newPage();
  const secret = process.env.DANCEGEN_OWNER_SECRET;
  if (secret) {
    await page.evaluateOnNewDocument((s) => {
      window.localStorage.setItem('dancegen-owner-secret', s);
    }, secret);
  }
  return page;
}
