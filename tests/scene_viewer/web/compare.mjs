// Image comparisons shared by the browser tests: masks of a screenshot and of scene-render's
// render of the same file, and the page report's checks. Failures throw.

/// Pixels of the cars' blue body colour, whatever the shading.
export function carBlue(png) {
    const mask = new Uint8Array(png.width * png.height);
    for (let i = 0; i < mask.length; ++i) {
        const r = png.data[4 * i], g = png.data[4 * i + 1], b = png.data[4 * i + 2];
        mask[i] = b > 35 && b > 3 * Math.max(r, g) + 30 ? 1 : 0;
    }
    return mask;
}

/// Pixels that differ from the lit background (205, 215, 228) by more than `threshold`.
export function foreground(png, threshold) {
    const mask = new Uint8Array(png.width * png.height);
    for (let i = 0; i < mask.length; ++i) {
        const d = Math.abs(png.data[4 * i] - 205) + Math.abs(png.data[4 * i + 1] - 215) +
                  Math.abs(png.data[4 * i + 2] - 228);
        mask[i] = d > threshold ? 1 : 0;
    }
    return mask;
}

/// The mask grown by r pixels (square neighbourhood, separable).
export function dilate(mask, w, h, r) {
    const rows = new Uint8Array(mask.length);
    for (let y = 0; y < h; ++y) {
        for (let x = 0; x < w; ++x) {
            let on = 0;
            for (let dx = -r; dx <= r && !on; ++dx) {
                const xx = x + dx;
                if (xx >= 0 && xx < w && mask[y * w + xx]) on = 1;
            }
            rows[y * w + x] = on;
        }
    }
    const out = new Uint8Array(mask.length);
    for (let y = 0; y < h; ++y) {
        for (let x = 0; x < w; ++x) {
            let on = 0;
            for (let dy = -r; dy <= r && !on; ++dy) {
                const yy = y + dy;
                if (yy >= 0 && yy < h && rows[yy * w + x]) on = 1;
            }
            out[y * w + x] = on;
        }
    }
    return out;
}

/// Share of a's pixels farther than r pixels from every pixel of b.
export function outsideShare(a, b, w, h, r) {
    const grown = dilate(b, w, h, r);
    let count = 0, outside = 0;
    for (let i = 0; i < a.length; ++i) {
        if (!a[i]) continue;
        ++count;
        if (!grown[i]) ++outside;
    }
    return count ? outside / count : 0;
}

export function checkReport(report) {
    if (report.errors.length) throw new Error('the page logged errors: ' + report.errors.join(' | '));
    if (report.outside.length) throw new Error('requests outside the folder: ' + report.outside.join(' '));
    if (report.requests < 5) throw new Error('only ' + report.requests + ' requests seen: listener broken?');
}

/// Fails unless two masks agree: IoU >= 0.85 and at most 2 % of either farther than 3 px
/// from the other.
export function compareMasks(ma, mb, a, what, shot, reference) {
    const count = (m) => m.reduce((s, v) => s + v, 0);
    let both = 0, either = 0;
    for (let i = 0; i < ma.length; ++i) {
        both += ma[i] & mb[i];
        either += ma[i] | mb[i];
    }
    const iou = both / either;
    const viewerOut = outsideShare(ma, mb, a.width, a.height, 3);
    const referenceOut = outsideShare(mb, ma, a.width, a.height, 3);
    console.log(`${what} px: viewer ${count(ma)}, scene-render ${count(mb)}; IoU ${iou.toFixed(3)};` +
                ` farther than 3 px: viewer ${(100 * viewerOut).toFixed(2)} %,` +
                ` scene-render ${(100 * referenceOut).toFixed(2)} %`);
    if (count(mb) < 2000) throw new Error(`the reference render shows almost no ${what} pixels`);
    if (viewerOut > 0.02 || referenceOut > 0.02 || iou < 0.85) {
        throw new Error(`the viewer and scene-render disagree on ${what} pixels (see ${shot} and ${reference})`);
    }
}
