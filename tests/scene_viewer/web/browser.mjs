// Shared by the browser tests and the viewer benchmark: Debian's chromium driven by
// playwright-core (never a downloaded browser), and PNG reading through pngjs.
import { createRequire } from 'node:module';
import fs from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';

/// Exit code CTest reads as "skipped" (SKIP_RETURN_CODE).
export const kSkip = 77;

export function skip(reason) {
    console.log('SKIPPED: ' + reason);
    process.exit(kSkip);
}

/// playwright-core and pngjs from the project's npm folder, or a skip when they are missing.
export function loadModules(nodeModules) {
    const require = createRequire(path.join(path.resolve(nodeModules), 'noop.js'));
    try {
        return { playwright: require('playwright-core'), PNG: require('pngjs').PNG };
    } catch (e) {
        skip('npm packages missing in ' + nodeModules + ' (scripts/install-deps.sh): ' + e.message);
    }
}

export const kChromiumFlags = [
    '--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
    '--disable-component-update', '--disable-sync', '--no-first-run',
    '--enable-unsafe-swiftshader', '--use-angle=swiftshader',
];

/// Launches the chromium at `executable` (Playwright gives it an empty temporary profile) and
/// opens a context; skips when it is missing.
export async function launch(playwright, executable) {
    if (!executable || !fs.existsSync(executable)) skip('chromium not found (' + executable + ')');
    const browser = await playwright.chromium.launch({
        executablePath: executable, headless: true, args: kChromiumFlags,
    });
    const context = await browser.newContext({ viewport: { width: 1280, height: 720 },
                                               deviceScaleFactor: 1 });
    context.on('close', () => browser.close());
    return context;
}

/// Opens the viewer folder's index.html from disk; records console errors, page errors and
/// every request that leaves the folder.
export async function openViewer(context, folder, query, viewport) {
    const page = await context.newPage();
    if (viewport) await page.setViewportSize(viewport);
    const base = pathToFileURL(path.resolve(folder)).href + '/';
    const report = { errors: [], outside: [], requests: 0 };
    page.on('console', (m) => { if (m.type() === 'error') report.errors.push(m.text()); });
    page.on('pageerror', (e) => report.errors.push(String(e)));
    page.on('request', (r) => {
        ++report.requests;
        const url = r.url();
        // blob: and data: URLs are the page's own memory (glTF images, the empty favicon).
        if (!url.startsWith(base) && !url.startsWith('blob:') && !url.startsWith('data:')) {
            report.outside.push(url);
        }
    });
    const started = Date.now();
    await page.goto(base + 'index.html' + (query || ''));
    await page.evaluate(() => window.viewer.ready);
    report.loadMs = Date.now() - started;
    return { page, report };
}

export function readPng(PNG, file) {
    return PNG.sync.read(fs.readFileSync(file));
}
