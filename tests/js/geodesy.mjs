// WGS84 geodesy and 4x4 matrices for the tile checkers: geodetic <-> ECEF,
// the glTF y-up -> 3D Tiles z-up turn, and column-major matrix helpers.
// Angles in radians, lengths in metres. Written here (not taken from Cesium)
// so the checkers do not share code with the renderer they judge.

export const WGS84_A = 6378137.0;
export const WGS84_F = 1 / 298.257223563;
export const WGS84_E2 = WGS84_F * (2 - WGS84_F);

// Geodetic (lon, lat, h) on WGS84 -> ECEF [x, y, z]. Exact to rounding.
export function geodeticToEcef(lon, lat, h) {
  const sinLat = Math.sin(lat);
  const cosLat = Math.cos(lat);
  const n = WGS84_A / Math.sqrt(1 - WGS84_E2 * sinLat * sinLat);
  return [
    (n + h) * cosLat * Math.cos(lon),
    (n + h) * cosLat * Math.sin(lon),
    (n * (1 - WGS84_E2) + h) * sinLat,
  ];
}

// ECEF -> geodetic {lon, lat, h}. Fixed-point iteration on the latitude
// (Bowring's form); ten rounds converge to below 1e-12 rad for heights from
// -1e5 to 1e7 m. The height uses the form that stays accurate at the poles.
export function ecefToGeodetic(x, y, z) {
  const p = Math.hypot(x, y);
  const lon = Math.atan2(y, x);
  let lat = Math.atan2(z, p * (1 - WGS84_E2));
  for (let i = 0; i < 10; ++i) {
    const s = Math.sin(lat);
    const n = WGS84_A / Math.sqrt(1 - WGS84_E2 * s * s);
    const h = p * Math.cos(lat) + z * s - WGS84_A * Math.sqrt(1 - WGS84_E2 * s * s);
    const next = Math.atan2(z, p * (1 - (WGS84_E2 * n) / (n + h)));
    if (Math.abs(next - lat) < 1e-15) { lat = next; break; }
    lat = next;
  }
  const s = Math.sin(lat);
  const h = p * Math.cos(lat) + z * s - WGS84_A * Math.sqrt(1 - WGS84_E2 * s * s);
  return { lon, lat, h };
}

// Column-major 4x4 matrices, as glTF and 3D Tiles store them.
export const IDENTITY = Object.freeze([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]);

// 3D Tiles: glTF content is y-up; the runtime turns it to z-up before the
// tile transform: (x, y, z) -> (x, -z, y).
export const Y_UP_TO_Z_UP = Object.freeze([1, 0, 0, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 0, 0, 1]);
export const Z_UP_TO_Y_UP = Object.freeze([1, 0, 0, 0, 0, 0, -1, 0, 0, 1, 0, 0, 0, 0, 0, 1]);

export function multiply(a, b) {
  const r = new Array(16).fill(0);
  for (let c = 0; c < 4; ++c)
    for (let row = 0; row < 4; ++row) {
      let s = 0;
      for (let k = 0; k < 4; ++k) s += a[k * 4 + row] * b[c * 4 + k];
      r[c * 4 + row] = s;
    }
  return r;
}

export function translation(t) {
  return [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, t[0], t[1], t[2], 1];
}

// glTF node TRS -> matrix (T * R * S), quaternion [x, y, z, w].
export function fromTrs(t = [0, 0, 0], q = [0, 0, 0, 1], s = [1, 1, 1]) {
  const [x, y, z, w] = q;
  const r = [
    1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w),
    2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
    2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y),
  ];
  return [
    r[0] * s[0], r[1] * s[0], r[2] * s[0], 0,
    r[3] * s[1], r[4] * s[1], r[5] * s[1], 0,
    r[6] * s[2], r[7] * s[2], r[8] * s[2], 0,
    t[0], t[1], t[2], 1,
  ];
}

export function transformPoint(m, x, y, z) {
  return [
    m[0] * x + m[4] * y + m[8] * z + m[12],
    m[1] * x + m[5] * y + m[9] * z + m[13],
    m[2] * x + m[6] * y + m[10] * z + m[14],
  ];
}

// Inverse transpose of the upper 3x3, as a 4x4 with no translation: turns
// normals. Returns null for a singular matrix.
export function normalMatrix(m) {
  const a = m[0], b = m[4], c = m[8], d = m[1], e = m[5], f = m[9], g = m[2], h = m[6], i = m[10];
  const det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g);
  if (!Number.isFinite(det) || Math.abs(det) < 1e-300) return null;
  // cofactor matrix / det  == inverse transpose
  const co = [
    (e * i - f * h), -(d * i - f * g), (d * h - e * g),
    -(b * i - c * h), (a * i - c * g), -(a * h - b * g),
    (b * f - c * e), -(a * f - c * d), (a * e - b * d),
  ];
  // co is row-major cofactors C[r][c]; the inverse transpose is C / det.
  return [
    co[0] / det, co[3] / det, co[6] / det, 0,
    co[1] / det, co[4] / det, co[7] / det, 0,
    co[2] / det, co[5] / det, co[8] / det, 0,
    0, 0, 0, 1,
  ];
}
