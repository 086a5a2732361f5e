//! The fluid simulation: a shallow layer of water on a paper height field, after Curtis,
//! Anderson, Seims, Fleischer and Salesin, *Computer-Generated Watercolor* (SIGGRAPH 1997),
//! §4.3–4.6, with the simplifications and constants of the project's recipe
//! (`shared/notes/watercolor-generator.md`, step 3).
//!
//! Layout: cells are row-major `w × h`. Velocities live on a staggered grid: `u` on the
//! vertical faces (`h × (w+1)`, `u[y][x]` between cells `x−1` and `x`), `v` on the
//! horizontal faces (`(h+1) × w`, `v[y][x]` between cells `y−1` and `y`). A face is *open*
//! when both its cells are wet; closed faces carry no velocity, so nothing leaves the wet area.

use super::Paper;
use super::blur::blur_xy;
use crate::rng::SplitMix64;

/// The per-step constants, derived from [`super::GeneratorParams`].
#[derive(Clone, Debug)]
pub(crate) struct SimParams {
    /// Viscosity μ.
    pub viscosity: f32,
    /// Viscous drag κ.
    pub drag: f32,
    /// Strength of the downhill force `−∇h`.
    pub slope: f32,
    /// Constant acceleration (a tilted sheet): terminal drift speed × κ, px/step².
    pub tilt: [f32; 2],
    /// Edge darkening η (Curtis's `FlowOutward`).
    pub edge_darkening: f32,
    /// σ of the wet-mask blur used by edge darkening, pixels.
    pub edge_sigma: f32,
    /// Pigment diffusion rate across open faces.
    pub diffusion: f32,
    /// Pigment density ρ (deposition rate).
    pub density: f32,
    /// Staining power ω (how reluctantly deposited pigment lifts again).
    pub staining: f32,
    /// Granulation γ (how strongly paper valleys collect pigment).
    pub granulation: f32,
    /// Scale of the wet-front threshold (higher: slower, more pressure before it moves).
    pub front_threshold: f32,
    /// Amplitude of the random part of the wet-front threshold.
    pub front_noise: f32,
    /// Water source amplitude `q(0)`.
    pub source: f32,
    /// Decay time of the source, steps.
    pub source_decay: f32,
    /// Pigment added per unit of water (`g += load · q · D`).
    pub load: f32,
    /// Decay time of the pigment in the source, steps (the drop's paint runs out before
    /// its water does, so later water pushes pigment outwards).
    pub load_decay: f32,
    /// How much flowing water keeps pigment from settling: ρ_eff = ρ / (1 + k |v|).
    pub flow_suspend: f32,
}

/// The simulation state.
pub(crate) struct Sim {
    pub w: usize,
    pub h: usize,
    pub paper: Paper,
    pub params: SimParams,
    u: Vec<f32>,
    v: Vec<f32>,
    /// Pressure p.
    p: Vec<f32>,
    /// Pigment suspended in water g.
    pub g: Vec<f32>,
    /// Pigment deposited on the paper d.
    pub d: Vec<f32>,
    /// Wet-area mask M.
    pub wet: Vec<bool>,
    /// Drop profile D (sum of the drops' Gaussians), where water and pigment are added.
    drop: Vec<f32>,
    /// Steps simulated so far.
    pub t: usize,
    rng: SplitMix64,
    /// Open flags of the `u` faces (both cells wet), refreshed every step.
    ou: Vec<bool>,
    /// Open flags of the `v` faces.
    ov: Vec<bool>,
}

/// A drop: center and radius in pixels, and when (step) it lands.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Drop {
    pub x: f32,
    pub y: f32,
    pub r: f32,
}

impl Sim {
    pub fn new(w: usize, h: usize, paper: Paper, params: SimParams, drops: &[Drop], mut rng: SplitMix64) -> Sim {
        let n = w * h;
        let mut wet = vec![false; n];
        let mut drop = vec![0.0f32; n];
        for dr in drops {
            // A wobbly disc r < R(1 + 0.15 sin 3θ + 0.1 sin 5θ), random phases.
            let (ph3, ph5) = (rng.range(0.0, 6.3), rng.range(0.0, 6.3));
            for y in 0..h {
                for x in 0..w {
                    let (dx, dy) = (x as f32 - dr.x, y as f32 - dr.y);
                    let r = (dx * dx + dy * dy).sqrt();
                    let th = dy.atan2(dx);
                    let edge = dr.r * (1.0 + 0.15 * (3.0 * th + ph3).sin() + 0.1 * (5.0 * th + ph5).sin());
                    let i = y * w + x;
                    if r < edge {
                        wet[i] = true;
                    }
                    let s = r / (0.85 * dr.r);
                    drop[i] += (-s * s).exp();
                }
            }
        }
        Sim {
            w,
            h,
            paper,
            params,
            u: vec![0.0; h * (w + 1)],
            v: vec![0.0; (h + 1) * w],
            p: vec![0.0; n],
            g: vec![0.0; n],
            d: vec![0.0; n],
            wet,
            drop,
            t: 0,
            rng,
            ou: vec![false; h * (w + 1)],
            ov: vec![false; (h + 1) * w],
        }
    }

    fn refresh_open(&mut self) {
        let (w, h) = (self.w, self.h);
        for y in 0..h {
            for x in 0..=w {
                self.ou[y * (w + 1) + x] = x > 0 && x < w && self.wet[y * w + x - 1] && self.wet[y * w + x];
            }
        }
        for y in 0..=h {
            for x in 0..w {
                self.ov[y * w + x] = y > 0 && y < h && self.wet[(y - 1) * w + x] && self.wet[y * w + x];
            }
        }
    }

    #[inline]
    fn open_u(&self, x: usize, y: usize) -> bool {
        self.ou[y * (self.w + 1) + x]
    }

    #[inline]
    fn open_v(&self, x: usize, y: usize) -> bool {
        self.ov[y * self.w + x]
    }

    /// Water source strength q at the current step.
    fn q(&self, growing: bool) -> f32 {
        if !growing {
            return 0.0;
        }
        self.params.source * (-(self.t as f32) / self.params.source_decay).exp()
    }

    /// One simulation step. `growing` false freezes the wet front and stops the source (the
    /// drying phase, where pigment keeps flowing to the rim and settles).
    pub fn step(&mut self, growing: bool) {
        self.refresh_open();
        let q = self.q(growing);
        // Pigment arrives with the water, but the drop's paint runs out sooner.
        if q > 0.0 {
            let load = self.params.load * (-(self.t as f32) / self.params.load_decay).exp();
            for i in 0..self.w * self.h {
                if self.wet[i] {
                    self.g[i] += load * q * self.drop[i];
                }
            }
        }
        self.update_velocities();
        self.relax_divergence(q);
        self.flow_outward(growing);
        self.move_pigment();
        self.diffuse_pigment();
        self.transfer_pigment();
        if growing {
            self.grow_front();
        }
        self.t += 1;
    }

    /// A one-line summary of the state, for tuning (`-vv`).
    pub fn stats(&self) -> String {
        let wet: Vec<usize> = (0..self.w * self.h).filter(|&i| self.wet[i]).collect();
        let n = wet.len().max(1) as f32;
        let vmax = self.u.iter().chain(&self.v).fold(0.0f32, |m, &a| m.max(a.abs()));
        let vmean = self.u.iter().chain(&self.v).map(|a| a.abs()).sum::<f32>() / n / 2.0;
        let pmean = wet.iter().map(|&i| self.p[i]).sum::<f32>() / n;
        let pmax = wet.iter().map(|&i| self.p[i]).fold(f32::MIN, f32::max);
        let pmin = wet.iter().map(|&i| self.p[i]).fold(f32::MAX, f32::min);
        let g: f32 = self.g.iter().sum();
        let d: f32 = self.d.iter().sum();
        format!(
            "t {} wet {} |v| max {vmax:.3} mean {vmean:.4} p {pmin:.2}/{pmean:.2}/{pmax:.2} g {g:.1} d {d:.1}",
            self.t,
            wet.len()
        )
    }

    fn update_velocities(&mut self) {
        let (w, h) = (self.w, self.h);
        let hh = &self.paper.height;
        let sp = self.params.clone();
        // Downhill force.
        for y in 0..h {
            for x in 1..w {
                self.u[y * (w + 1) + x] -= sp.slope * (hh[y * w + x] - hh[y * w + x - 1]);
            }
        }
        for y in 1..h {
            for x in 0..w {
                self.v[y * w + x] -= sp.slope * (hh[y * w + x] - hh[(y - 1) * w + x]);
            }
        }
        let vmax = self.u.iter().chain(&self.v).fold(0.0f32, |m, &a| m.max(a.abs()));
        let n = (vmax.ceil() as usize).max(1);
        let dt = 1.0 / n as f32;
        let (wu, wv) = (w + 1, w);
        for _ in 0..n {
            let u0 = self.u.clone();
            let v0 = self.v.clone();
            for y in 0..h {
                for x in 1..w {
                    let i = y * wu + x;
                    if !self.open_u(x, y) {
                        self.u[i] = 0.0;
                        continue;
                    }
                    let c = u0[i];
                    let l = u0[i - 1];
                    let r = u0[i + 1];
                    let t = if y > 0 { u0[i - wu] } else { c };
                    let b = if y + 1 < h { u0[i + wu] } else { c };
                    let lap = l + r + t + b - 4.0 * c;
                    let dp = self.p[y * w + x - 1] - self.p[y * w + x];
                    let nu = c + dt * (sp.viscosity * lap + dp - sp.drag * c + sp.tilt[0]);
                    self.u[i] = nu.clamp(-1.0, 1.0);
                }
                self.u[y * wu] = 0.0;
                self.u[y * wu + w] = 0.0;
            }
            for y in 0..=h {
                for x in 0..w {
                    let i = y * wv + x;
                    if !self.open_v(x, y) {
                        self.v[i] = 0.0;
                        continue;
                    }
                    let c = v0[i];
                    let t = v0[i - wv];
                    let b = v0[i + wv];
                    let l = if x > 0 { v0[i - 1] } else { c };
                    let r = if x + 1 < w { v0[i + 1] } else { c };
                    let lap = l + r + t + b - 4.0 * c;
                    let dp = self.p[(y - 1) * w + x] - self.p[y * w + x];
                    let nv = c + dt * (sp.viscosity * lap + dp - sp.drag * c + sp.tilt[1]);
                    self.v[i] = nv.clamp(-1.0, 1.0);
                }
            }
        }
    }

    /// Makes the flow (nearly) divergence-free, except where the drop adds water (`q·D`).
    fn relax_divergence(&mut self, q: f32) {
        let (w, h) = (self.w, self.h);
        let wu = w + 1;
        for _ in 0..50 {
            let mut max_delta = 0.0f32;
            // Red-black order: a lexicographic sweep would favour one diagonal direction.
            for colour in 0..2 {
                for y in 0..h {
                    let mut x = (y + colour) % 2;
                    while x < w {
                        let c = y * w + x;
                        if self.wet[c] {
                            let (il, ir) = (y * wu + x, y * wu + x + 1);
                            let (it, ib) = (y * w + x, (y + 1) * w + x);
                            let div = self.u[ir] - self.u[il] + self.v[ib] - self.v[it];
                            let delta = -0.1 * (div - q * self.drop[c]);
                            self.p[c] += delta;
                            if self.ou[ir] {
                                self.u[ir] += delta;
                            }
                            if self.ou[il] {
                                self.u[il] -= delta;
                            }
                            if self.ov[ib] {
                                self.v[ib] += delta;
                            }
                            if self.ov[it] {
                                self.v[it] -= delta;
                            }
                            max_delta = max_delta.max(delta.abs());
                        }
                        x += 2;
                    }
                }
            }
            if max_delta < 0.01 {
                break;
            }
        }
    }

    /// Edge darkening (Curtis's `FlowOutward`): lower the pressure near the wet front so
    /// water, and the pigment in it, flows towards the rim.
    fn flow_outward(&mut self, growing: bool) {
        let (w, h) = (self.w, self.h);
        let m: Vec<f32> = self.wet.iter().map(|&b| if b { 1.0 } else { 0.0 }).collect();
        let blurred = blur_xy(&m, w, h, self.params.edge_sigma, self.params.edge_sigma);
        // While drying, evaporation at the rim pulls harder (the coffee-ring effect).
        let eta = if growing { self.params.edge_darkening } else { 2.0 * self.params.edge_darkening };
        for ((p, &wet), &b) in self.p.iter_mut().zip(&self.wet).zip(&blurred) {
            if wet {
                *p -= eta * (1.0 - b);
            }
        }
    }

    /// Upwind transport of the suspended pigment with the velocity field. Sub-steps keep
    /// every face's flux under a quarter of what its upwind cell holds.
    fn move_pigment(&mut self) {
        let (w, h) = (self.w, self.h);
        let wu = w + 1;
        let vmax = self.u.iter().chain(&self.v).fold(0.0f32, |m, &a| m.max(a.abs()));
        let n = ((4.0 * vmax).ceil() as usize).max(1);
        let dt = 1.0 / n as f32;
        for _ in 0..n {
            let mut ng = self.g.clone();
            for y in 0..h {
                for x in 1..w {
                    let vel = self.u[y * wu + x];
                    if vel == 0.0 {
                        continue;
                    }
                    let (l, r) = (y * w + x - 1, y * w + x);
                    let flux = dt * vel * if vel > 0.0 { self.g[l] } else { self.g[r] };
                    ng[l] -= flux;
                    ng[r] += flux;
                }
            }
            for y in 1..h {
                for x in 0..w {
                    let vel = self.v[y * w + x];
                    if vel == 0.0 {
                        continue;
                    }
                    let (t, b) = ((y - 1) * w + x, y * w + x);
                    let flux = dt * vel * if vel > 0.0 { self.g[t] } else { self.g[b] };
                    ng[t] -= flux;
                    ng[b] += flux;
                }
            }
            for v in &mut ng {
                *v = v.max(0.0);
            }
            self.g = ng;
        }
    }

    /// Paper-guided diffusion: pigment spreads faster where the paper holds more water.
    fn diffuse_pigment(&mut self) {
        let (w, h) = (self.w, self.h);
        let k = self.params.diffusion;
        let cap = &self.paper.capacity;
        let mut ng = self.g.clone();
        for y in 0..h {
            for x in 0..w {
                let a = y * w + x;
                if !self.wet[a] {
                    continue;
                }
                if x + 1 < w && self.wet[a + 1] {
                    let f = k * (0.4 + 0.5 * (cap[a] + cap[a + 1])) * (self.g[a] - self.g[a + 1]);
                    ng[a] -= f;
                    ng[a + 1] += f;
                }
                if y + 1 < h && self.wet[a + w] {
                    let f = k * (0.4 + 0.5 * (cap[a] + cap[a + w])) * (self.g[a] - self.g[a + w]);
                    ng[a] -= f;
                    ng[a + w] += f;
                }
            }
        }
        self.g = ng;
    }

    /// Adsorption and desorption (Curtis's `TransferPigment`).
    fn transfer_pigment(&mut self) {
        let sp = &self.params;
        let (omega, gamma) = (sp.staining, sp.granulation);
        let (w, wu) = (self.w, self.w + 1);
        for i in 0..self.w * self.h {
            if !self.wet[i] {
                continue;
            }
            let (x, y) = (i % w, i / w);
            let speed = 0.5
                * (self.u[y * wu + x].abs()
                    + self.u[y * wu + x + 1].abs()
                    + self.v[y * w + x].abs()
                    + self.v[(y + 1) * w + x].abs());
            let rho = sp.density / (1.0 + sp.flow_suspend * speed);
            let hgt = self.paper.height[i];
            let down = self.g[i] * ((1.0 - hgt * gamma) * rho).clamp(0.0, 1.0);
            let up = self.d[i] * ((1.0 + (hgt - 1.0) * gamma) * rho / omega).clamp(0.0, 1.0);
            let (d, g) = (self.d[i] + down - up, self.g[i] + up - down);
            self.d[i] = d.max(0.0);
            self.g[i] = g.max(0.0);
        }
    }

    /// The wet front advances into a dry cell when the mean pressure of the wet cells
    /// around it (a disc of radius 2), scaled by how much of that disc is wet, beats a
    /// threshold that is lower in the paper's valleys and freshly random every step. The disc
    /// keeps the growth isotropic (a 4- or 8-neighbour rule grows squares and diamonds) and
    /// rounds off thin spikes while letting bays fill in.
    fn grow_front(&mut self) {
        const DISC: [(i32, i32); 20] = [
            (-1, -2),
            (0, -2),
            (1, -2),
            (-2, -1),
            (-1, -1),
            (0, -1),
            (1, -1),
            (2, -1),
            (-2, 0),
            (-1, 0),
            (1, 0),
            (2, 0),
            (-2, 1),
            (-1, 1),
            (0, 1),
            (1, 1),
            (2, 1),
            (-1, 2),
            (0, 2),
            (1, 2),
        ];
        let (w, h) = (self.w, self.h);
        let sp = self.params.clone();
        let tilt_len = sp.tilt[0].hypot(sp.tilt[1]);
        // Terminal drift speed of the tilt, and its direction.
        let drift = tilt_len / sp.drag.max(1e-6);
        let tdir = if tilt_len > 0.0 { [sp.tilt[0] / tilt_len, sp.tilt[1] / tilt_len] } else { [0.0, 0.0] };
        let mut newly = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let c = y * w + x;
                if self.wet[c] {
                    continue;
                }
                // Only cells touching the wet area (8-neighbourhood) can become wet.
                let touches = (y.saturating_sub(1)..(y + 2).min(h))
                    .any(|yy| (x.saturating_sub(1)..(x + 2).min(w)).any(|xx| self.wet[yy * w + xx]));
                if !touches {
                    continue;
                }
                let (mut n, mut psum, mut cx, mut cy) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
                for &(dx, dy) in &DISC {
                    let (nx, ny) = (x as i32 + dx, y as i32 + dy);
                    if nx < 0 || ny < 0 || nx >= w as i32 || ny >= h as i32 {
                        continue;
                    }
                    let ni = ny as usize * w + nx as usize;
                    if self.wet[ni] {
                        n += 1.0;
                        psum += self.p[ni];
                        cx += dx as f32;
                        cy += dy as f32;
                    }
                }
                if n == 0.0 {
                    continue;
                }
                let frac = n / DISC.len() as f32;
                let mut pressure = psum / n * (frac / 0.4).sqrt();
                if drift > 0.0 {
                    // Downstream of the wet area (away from its local centroid, along the
                    // drift) the front advances more easily.
                    let len = cx.hypot(cy).max(1e-6);
                    pressure -= 10.0 * drift * (cx * tdir[0] + cy * tdir[1]) / len;
                }
                let r = self.rng.next_f32();
                let threshold = sp.front_threshold * (0.5 + (1.0 - self.paper.smooth[c]) + sp.front_noise * r);
                if pressure > threshold {
                    newly.push(c);
                }
            }
        }
        for c in newly {
            self.wet[c] = true;
        }
    }
}
