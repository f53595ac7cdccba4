//! Probe (temporary): chute flow diagnostics over time.
use regolith::body::{Phase, PointStates, Points};
use regolith::{Regolith, Scene, Simulation};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let deg: f64 = args[0].parse().unwrap();
    let every: f64 = args[1].parse().unwrap();
    let mut sets: Vec<String> = args[2..].to_vec();
    let th = deg.to_radians();
    sets.insert(0, format!("gravity=({}, {})", 9.81 * th.sin(), -9.81 * th.cos()));
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/chute_flow.ron");
    let (scene, _) = Scene::load(&path, &sets, &Regolith::default().registries()).unwrap_or_else(|e| panic!("{e}"));
    let h0: f64 = 0.1;
    let (mu_s, mu_2, i0, d, phi, g) = (0.32, 0.598, 0.278, 5e-3, 0.79, 9.81);
    let i = i0 * (th.tan() - mu_s) / (mu_2 - th.tan());
    let k = (2.0 / 3.0) * (i / d) * (phi * g * th.cos()).sqrt();
    let us = k * h0.powf(1.5);
    let width = scene.domain.size.x;
    let mut sim = Simulation::new(&scene);
    let h = sim.grid().cell_size;
    let mut next = 0.0;
    let t0 = std::time::Instant::now();
    println!("# u_s analytic {us:.3}  mean {:.3}", 0.6 * us);
    loop {
        if sim.clock().time >= next - 1e-12 {
            next += every;
            let mut q = sim.world.query::<(&Points, &PointStates)>();
            let (p, s) = q.single(&sim.world).unwrap();
            let n = p.len();
            let mut ys: Vec<f64> = p.position.iter().map(|x| x.y).collect();
            ys.sort_by(f64::total_cmp);
            let top = ys[(0.99 * (n - 1) as f64) as usize];
            let ybar = ys.iter().sum::<f64>() / n as f64;
            let vol: f64 = p.volume.iter().sum();
            let mass: f64 = p.mass.iter().sum();
            let gas = s.phase.iter().filter(|ph| **ph == Phase::Disconnected).count() as f64 / n as f64;
            let vmean = p.velocity.iter().zip(&p.mass).map(|(v, m)| v.x * m).sum::<f64>() / mass;
            let nb = (h0 / h).round() as usize;
            let mut bins = vec![(0.0, 0usize); nb + 4];
            for (x, v) in p.position.iter().zip(&p.velocity) {
                let b = ((x.y / h) as usize).min(nb + 3);
                bins[b].0 += v.x;
                bins[b].1 += 1;
            }
            let mut err2 = 0.0;
            let mut cnt = 0;
            for (b, (sum, c)) in bins.iter().enumerate().take(nb) {
                if *c == 0 { continue; }
                let y = (b as f64 + 0.5) * h;
                let ua = k * (h0.powf(1.5) - (h0 - y).max(0.0).powf(1.5));
                err2 += (sum / *c as f64 - ua).powi(2);
                cnt += 1;
            }
            let rms = (err2 / cnt.max(1) as f64).sqrt() / us;
            // honesty: summed volume vs the area 2*ybar*width (uniform layer)
            let v95 = {
                let mut sp: Vec<f64> = p.velocity.iter().map(|v| v.length()).collect();
                sp.sort_by(f64::total_cmp);
                sp[(0.95 * (n - 1) as f64) as usize]
            };
            let pmean = p.stress.iter().map(|t| t.pressure()).sum::<f64>() / n as f64;
            println!(
                "t={:6.2} top={:.4} ybar={:.4} sumV/(W*2ybar)={:.4} sumV/(W*H0)={:.5} gas={:.3} vmean={:.3} rms={:.3} v95={:.3} pmean={:.1} wall={:.0}s",
                sim.clock().time, top, ybar, vol / (width * 2.0 * ybar), vol / (width * h0), gas, vmean, rms, v95, pmean,
                t0.elapsed().as_secs_f64()
            );
        }
        if sim.finished() { break; }
        if let Err(e) = sim.step() { println!("fault: {e}"); break; }
    }
}
