use slidestack::dynamics::*;
use slidestack::motion::read_record;
use std::path::Path;
fn main() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/records");
    let cases: &[(&str, f64, &[f64], &[f64])] = &[
        ("RSN960_NORTHR_LOS270.AT2", 1.0, &[0.5, 0.5], &[0.2, 0.1]),
        ("RSN829_CAPEMEND_RIO360.AT2", 1.0, &[0.5, 0.5], &[0.2, 0.1]),
        ("RSN829_CAPEMEND_RIO360.AT2", 0.5, &[1.0], &[0.15]),
        ("RSN1633_MANJIL_ABBAR--L.AT2", 0.5, &[1.0], &[0.15]),
        ("RSN960_NORTHR_LOS270.AT2", 0.3, &[0.5, 0.5], &[5.0, 5.0]),
        ("RSN829_CAPEMEND_RIO360.AT2", 0.3, &[0.5, 0.5], &[5.0, 5.0]),
    ];
    for (rec, t, a, m) in cases {
        let r = read_record(&dir.join(rec)).unwrap();
        let acc = r.accel_mps2(1.0);
        let g = Ground { dt_s: r.dt_s, accel_mps2: &acc };
        let sys = System::new(&SystemSpec::new(*t, a, m)).unwrap();
        let ex = simulate_exact(&sys, &g, &ExactOptions { history: true, ..Default::default() }).unwrap();
        let eh = ex.history.as_ref().unwrap();
        let nb = eh.bodies;
        println!("== {rec} T={t} a={a:?} mu={m:?}: exact peak {:.10e} at {:.6} s, switches {}", ex.peak_displacement_m, ex.peak_displacement_time_s, ex.switches);
        for s in [100usize, 200, 500, 1000, 2000, 5000] {
            let rk = simulate_rk4(&sys, &g, s, true).unwrap();
            let rh = rk.history.as_ref().unwrap();
            let p = ex.peak_displacement_m;
            let mut maxe = 0.0f64; let mut at = 0; let mut first = None;
            for k in 0..eh.rows() {
                let e = (rh.displacement_m[k*nb] - eh.displacement_m[k*nb]).abs() / p;
                if e > maxe { maxe = e; at = k; }
                if first.is_none() && e > 1e-7 { first = Some(k); }
            }
            let nint = nb - 1;
            let cdiff = (0..eh.rows()).find(|&k| rh.contact[k*nint..(k+1)*nint] != eh.contact[k*nint..(k+1)*nint]);
            println!("  rk4 x{s}: peak {:+.3e} at {:.6} s; hist err {:.3e} at t={:.3}; first >1e-7 at t={:?}; first contact diff at t={:?} ex {:?} rk {:?}; slip {:?} vs {:?}",
                (rk.peak_displacement_m - p)/p, rk.peak_displacement_time_s, maxe, eh.time_s[at],
                first.map(|k| eh.time_s[k]), cdiff.map(|k| eh.time_s[k]),
                cdiff.map(|k| &eh.contact[k*nint..(k+1)*nint]), cdiff.map(|k| &rh.contact[k*nint..(k+1)*nint]),
                ex.residual_slip_m, rk.residual_slip_m);
        }
    }
}
