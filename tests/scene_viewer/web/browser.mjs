// Shared by the browser tests and the viewer benchmark: Debian's chromium driven by
// playwright-core (never a downloaded browser), and PNG reading through pngjs.
import { spawnSync } from 'node:child_process';
import { createRequire } from 'node:module';
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { pathToFileURL } from 'node:url';

/// Exit code CTest reads as "skipped" (SKIP_RETURN_CODE).
export const kSkip = 77;

export function skip(reason) {
    console.log('SKIPPED: ' + reason);
    process.exit(kSkip);
}

/// Fails the test with a message (exit 1).
export function fail(message) {
    console.error('FAIL: ' + message);
    process.exit(1);
}

/// Runs a tool of the project; fails the test when it exits non-zero.
export function runTool(exe, args) {
    const r = spawnSync(exe, args, { encoding: 'utf8' });
    if (r.status !== 0) fail(path.basename(exe) + ' ' + args.join(' ') + ' exited ' + r.status + ': ' + r.stderr);
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

const kTypes = { '.html': 'text/html', '.js': 'text/javascript', '.css': 'text/css',
                 '.png': 'image/png', '.glb': 'model/gltf-binary' };

/// A static file server for `folder` on the loopback interface (a free port); close() stops it.
export async function serveFolder(folder) {
    const root = path.resolve(folder);
    const server = http.createServer((request, response) => {
        const file = path.join(root, decodeURIComponent(new URL(request.url, 'http://x').pathname));
        if (!file.startsWith(root + path.sep) || !fs.existsSync(file) || !fs.statSync(file).isFile()) {
            response.writeHead(404).end();
            return;
        }
        response.writeHead(200, { 'content-type': kTypes[path.extname(file)] || 'application/octet-stream' });
        fs.createReadStream(file).pipe(response);
    });
    await new Promise((resolve) => server.listen(0, '127.0.0.1', resolve));
    return { url: `http://127.0.0.1:${server.address().port}/`, close: () => server.close() };
}

/// Opens the viewer's index.html, from disk or (`folder` an http URL ending in /) a server;
/// records console errors, page errors and every request that leaves the folder.
export async function openViewer(context, folder, query, viewport) {
    const page = await context.newPage();
    if (viewport) await page.setViewportSize(viewport);
    const base = folder.startsWith('http') ? folder : pathToFileURL(path.resolve(folder)).href + '/';
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
