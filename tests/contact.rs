//! The contact selector against brute-force enumeration of every stick/slip pattern.

#![allow(clippy::needless_range_loop)]

mod common;

use common::Rng;
use slidestack::dynamics::{Contact, ContactSelector, G};

struct State {
    masses: Vec<f64>,
    external: Vec<f64>,
    lim_s: Vec<f64>,
    lim_k: Vec<f64>,
    /// Input contacts: Slip(d) for moving interfaces, Free for μ = 0, Stick for candidates.
    given: Vec<Contact>,
}

/// Forces and relative accelerations of a full pattern on a chain: [`evaluate_tree`] with
/// every interface on the body below it.
fn evaluate(st: &State, pattern: &[Contact]) -> (Vec<f64>, Vec<f64>) {
    let below: Vec<usize> = (0..pattern.len()).collect();
    evaluate_tree(st, &below, pattern)
}

/// Is the pattern Coulomb-consistent, with slack `tol` (relative)?
fn consistent(st: &State, pattern: &[Contact], tol: f64) -> bool {
    let below: Vec<usize> = (0..pattern.len()).collect();
    consistent_tree(st, &below, pattern, tol)
}

fn all_patterns(given: &[Contact]) -> Vec<Vec<Contact>> {
    let mut out = vec![given.to_vec()];
    for i in 0..given.len() {
        if given[i] != Contact::Stick {
            continue;
        }
        let mut next = Vec::new();
        for p in &out {
            for c in [Contact::Stick, Contact::Slip(1), Contact::Slip(-1)] {
                let mut q = p.clone();
                q[i] = c;
                next.push(q);
            }
        }
        out = next;
    }
    out
}

fn random_state(rng: &mut Rng, static_gap: bool) -> State {
    let n = 1 + rng.below(6);
    let masses: Vec<f64> = (0..=n).map(|_| rng.log_range(0.01, 10.0)).collect();
    let mut lim_s = Vec::new();
    let mut lim_k = Vec::new();
    let mut given = Vec::new();
    for i in 0..n {
        let normal: f64 = G * masses[i + 1..].iter().sum::<f64>();
        let mu_k = rng.range(0.02, 0.8);
        let mu_s = if static_gap {
            mu_k * rng.range(1.0, 2.0)
        } else {
            mu_k
        };
        lim_k.push(mu_k * normal);
        lim_s.push(mu_s * normal);
        given.push(match rng.below(4) {
            0 => Contact::Slip(if rng.unit() < 0.5 { 1 } else { -1 }),
            _ => Contact::Stick,
        });
    }
    let external = masses.iter().map(|m| m * G * 0.6 * rng.normal()).collect();
    State {
        masses,
        external,
        lim_s,
        lim_k,
        given,
    }
}

fn select(st: &State) -> Vec<Contact> {
    let n = st.given.len();
    let mut sel = ContactSelector::new(n);
    let mut contacts = st.given.clone();
    let mut force = vec![0.0; n];
    sel.select(
        &st.masses,
        &st.external,
        &st.lim_s,
        &st.lim_k,
        &mut contacts,
        &mut force,
    )
    .unwrap();
    // The forces it returns are those of its pattern.
    let (f_ref, _) = evaluate(st, &contacts);
    let scale = st
        .lim_s
        .iter()
        .chain(st.external.iter())
        .fold(0.0f64, |m, x| m.max(x.abs()));
    for i in 0..n {
        assert!(
            (force[i] - f_ref[i]).abs() <= 1e-9 * scale,
            "force {i}: {} vs {}",
            force[i],
            f_ref[i]
        );
    }
    contacts
}

/// `μ_s = μ_k`: exactly one pattern is consistent (generic states) and the selector returns it.
/// States where a looser or stricter slack (1e-9 vs 1e-12) changes the count are near-ties of
/// measure zero and are skipped; at most 2 % may be.
#[test]
fn unique_consistent_pattern_is_chosen() {
    let mut rng = Rng::new(7);
    let (mut checked, mut skipped) = (0, 0);
    for _ in 0..3000 {
        let st = random_state(&mut rng, false);
        let patterns = all_patterns(&st.given);
        let loose: Vec<_> = patterns
            .iter()
            .filter(|p| consistent(&st, p, 1e-9))
            .collect();
        let strict = patterns
            .iter()
            .filter(|p| consistent(&st, p, -1e-12))
            .count();
        if loose.len() != 1 || strict != 1 {
            skipped += 1;
            continue;
        }
        assert_eq!(
            &select(&st),
            loose[0],
            "masses {:?} ext {:?} given {:?}",
            st.masses,
            st.external,
            st.given
        );
        checked += 1;
    }
    assert!(skipped * 50 <= checked, "{skipped} near-ties of {checked}");
}

/// `μ_s > μ_k`: the chosen pattern is always among the consistent ones (progressive release).
#[test]
fn static_gap_choice_is_consistent() {
    let mut rng = Rng::new(11);
    let mut several = 0;
    for _ in 0..3000 {
        let st = random_state(&mut rng, true);
        let chosen = select(&st);
        assert!(
            consistent(&st, &chosen, 1e-9),
            "chosen {chosen:?} inconsistent for {:?}",
            st.given
        );
        let count = all_patterns(&st.given)
            .iter()
            .filter(|p| consistent(&st, p, 1e-9))
            .count();
        if count > 1 {
            several += 1;
        }
    }
    assert!(
        several > 50,
        "the sample must contain ambiguous states, got {several}"
    );
}

/// The documented rule on the simplest ambiguous state: a block at rest whose demand lies between
/// its kinetic and static limits may both stick and slip; progressive release keeps it stuck.
/// Above the static limit it slips, against the demand.
#[test]
fn progressive_release_sticks_when_static_friction_can_hold() {
    let masses = [1.0, 1.0];
    let (lim_s, lim_k) = ([0.3 * G], [0.2 * G]);
    // Structure pushed forward: the block must be dragged at 0.125 g (half the 0.25 g).
    for (push, expect) in [(0.5 * G, Contact::Stick), (0.7 * G, Contact::Slip(-1))] {
        let mut c = [Contact::Stick];
        let mut f = [0.0];
        ContactSelector::new(1)
            .select(&masses, &[push, 0.0], &lim_s, &lim_k, &mut c, &mut f)
            .unwrap();
        assert_eq!(c[0], expect);
        let expected_force = if expect == Contact::Stick {
            push / 2.0
        } else {
            lim_k[0]
        };
        assert!((f[0] - expected_force).abs() < 1e-12);
    }
}

/// A floor with several stacks: body 0 the floor, interface `i` under body `i + 1` and above
/// `below[i]`.
struct Tree {
    st: State,
    below: Vec<usize>,
}

/// Forces and relative accelerations of a full pattern, cluster by cluster (no QP): a
/// cluster's acceleration is its net known force over its mass; a stuck interface carries what
/// moves the part of its cluster above it (and what that part's slipping interfaces pull).
/// Interface `i` lies under body `i + 1` and above `below[i]`.
fn evaluate_tree(st: &State, below: &[usize], pattern: &[Contact]) -> (Vec<f64>, Vec<f64>) {
    let n = pattern.len();
    let mut force = vec![0.0; n];
    for i in 0..n {
        if let Contact::Slip(d) = pattern[i] {
            force[i] = -st.lim_k[i] * f64::from(d);
        }
    }
    // Cluster of each body: the lowest body reached through stuck interfaces.
    let mut cluster: Vec<usize> = (0..=n).collect();
    for i in 0..n {
        if pattern[i] == Contact::Stick {
            cluster[i + 1] = cluster[below[i]];
        }
    }
    let net = |b: usize, force: &[f64]| {
        let mut e = st.external[b];
        if b > 0 && pattern[b - 1] != Contact::Stick {
            e += force[b - 1];
        }
        for i in 0..n {
            if below[i] == b && pattern[i] != Contact::Stick {
                e -= force[i];
            }
        }
        e
    };
    let mut accel = vec![0.0; n + 1];
    for c in 0..=n {
        let members: Vec<usize> = (0..=n).filter(|&b| cluster[b] == c).collect();
        if members.is_empty() {
            continue;
        }
        let mass: f64 = members.iter().map(|&b| st.masses[b]).sum();
        let f: f64 = members.iter().map(|&b| net(b, &force)).sum();
        for &b in &members {
            accel[b] = f / mass;
        }
    }
    // A stuck interface: the bodies above it in its cluster (its subtree) need m·a − net.
    for i in (0..n).rev() {
        if pattern[i] != Contact::Stick {
            continue;
        }
        let mut subtree = vec![i + 1];
        for j in i + 1..n {
            if pattern[j] == Contact::Stick && subtree.contains(&below[j]) {
                subtree.push(j + 1);
            }
        }
        force[i] = subtree
            .iter()
            .map(|&b| st.masses[b] * accel[b] - net(b, &force))
            .sum();
    }
    let rel = (0..n).map(|i| accel[i + 1] - accel[below[i]]).collect();
    (force, rel)
}

fn consistent_tree(st: &State, below: &[usize], pattern: &[Contact], tol: f64) -> bool {
    let (force, rel) = evaluate_tree(st, below, pattern);
    pattern
        .iter()
        .enumerate()
        .all(|(i, c)| match (st.given[i], *c) {
            (Contact::Stick, Contact::Stick) => force[i].abs() <= st.lim_s[i] * (1.0 + tol),
            (Contact::Stick, Contact::Slip(d)) => {
                let scale = st.lim_s[i] / st.masses[i + 1].min(st.masses[below[i]]) + 1e-300;
                f64::from(d) * rel[i] > -tol * scale
            }
            (g, c) => g == c,
        })
}

/// Two to three stacks of one to three blocks on a floor.
fn random_tree(rng: &mut Rng, static_gap: bool) -> Tree {
    let stacks = 2 + rng.below(2);
    let mut below = Vec::new();
    for _ in 0..stacks {
        let blocks = 1 + rng.below(3);
        for b in 0..blocks {
            let i = below.len();
            below.push(if b == 0 { 0 } else { i });
        }
    }
    let n = below.len();
    let masses: Vec<f64> = (0..=n).map(|_| rng.log_range(0.01, 10.0)).collect();
    let (mut lim_s, mut lim_k, mut given) = (vec![], vec![], vec![]);
    for i in 0..n {
        // Normal force: the block and everything stacked on it.
        let mut above = vec![i + 1];
        for j in i + 1..n {
            if above.contains(&below[j]) {
                above.push(j + 1);
            }
        }
        let normal: f64 = G * above.iter().map(|&b| masses[b]).sum::<f64>();
        let mu_k = rng.range(0.02, 0.8);
        let mu_s = if static_gap {
            mu_k * rng.range(1.0, 2.0)
        } else {
            mu_k
        };
        lim_k.push(mu_k * normal);
        lim_s.push(mu_s * normal);
        given.push(match rng.below(4) {
            0 => Contact::Slip(if rng.unit() < 0.5 { 1 } else { -1 }),
            _ => Contact::Stick,
        });
    }
    let external = masses.iter().map(|m| m * G * 0.6 * rng.normal()).collect();
    Tree {
        st: State {
            masses,
            external,
            lim_s,
            lim_k,
            given,
        },
        below,
    }
}

fn select_tree(t: &Tree) -> Vec<Contact> {
    let st = &t.st;
    let n = st.given.len();
    let mut contacts = st.given.clone();
    let mut force = vec![0.0; n];
    ContactSelector::new(n)
        .select_tree(
            &t.below,
            &st.masses,
            &st.external,
            &st.lim_s,
            &st.lim_k,
            &mut contacts,
            &mut force,
        )
        .unwrap();
    let (f_ref, _) = evaluate_tree(st, &t.below, &contacts);
    let scale = st
        .lim_s
        .iter()
        .chain(st.external.iter())
        .fold(0.0f64, |m, x| m.max(x.abs()));
    for i in 0..n {
        assert!(
            (force[i] - f_ref[i]).abs() <= 1e-9 * scale,
            "force {i}: {} vs {}",
            force[i],
            f_ref[i]
        );
    }
    contacts
}

/// Several stacks on one floor, `μ_s = μ_k`: the unique consistent pattern over all of them,
/// found by brute force over every stick/slip pattern, is the one chosen.
#[test]
fn several_stacks_on_a_floor_get_the_unique_consistent_pattern() {
    let mut rng = Rng::new(23);
    let (mut checked, mut skipped, mut coupled) = (0, 0, 0);
    for _ in 0..3000 {
        let t = random_tree(&mut rng, false);
        let patterns = all_patterns(&t.st.given);
        let loose: Vec<_> = patterns
            .iter()
            .filter(|p| consistent_tree(&t.st, &t.below, p, 1e-9))
            .collect();
        let strict = patterns
            .iter()
            .filter(|p| consistent_tree(&t.st, &t.below, p, -1e-12))
            .count();
        if loose.len() != 1 || strict != 1 {
            skipped += 1;
            continue;
        }
        let chosen = select_tree(&t);
        assert_eq!(
            &chosen, loose[0],
            "below {:?} given {:?}",
            t.below, t.st.given
        );
        // Count states where two stacks' first interfaces both take part (the floor couples).
        let firsts: Vec<usize> = (0..t.below.len()).filter(|&i| t.below[i] == 0).collect();
        if firsts
            .iter()
            .filter(|&&i| t.st.given[i] == Contact::Stick)
            .count()
            >= 2
        {
            coupled += 1;
        }
        checked += 1;
    }
    assert!(skipped * 50 <= checked, "{skipped} near-ties of {checked}");
    assert!(coupled > 500, "coupled states: {coupled}");
}

/// `μ_s > μ_k` on several stacks: the chosen pattern is always among the consistent ones.
#[test]
fn several_stacks_with_a_static_gap_get_a_consistent_pattern() {
    let mut rng = Rng::new(29);
    for _ in 0..3000 {
        let t = random_tree(&mut rng, true);
        let chosen = select_tree(&t);
        assert!(
            consistent_tree(&t.st, &t.below, &chosen, 1e-9),
            "chosen {chosen:?} inconsistent for {:?} below {:?}",
            t.st.given,
            t.below
        );
    }
}

/// On a chain the tree selector is the chain selector, bit for bit.
#[test]
fn the_tree_selector_on_a_chain_is_the_chain_selector() {
    let mut rng = Rng::new(31);
    for _ in 0..2000 {
        let gap = rng.unit() < 0.5;
        let st = random_state(&mut rng, gap);
        let n = st.given.len();
        let below: Vec<usize> = (0..n).collect();
        let (mut c1, mut c2) = (st.given.clone(), st.given.clone());
        let (mut f1, mut f2) = (vec![0.0; n], vec![0.0; n]);
        let mut sel = ContactSelector::new(n);
        sel.select(
            &st.masses,
            &st.external,
            &st.lim_s,
            &st.lim_k,
            &mut c1,
            &mut f1,
        )
        .unwrap();
        sel.select_tree(
            &below,
            &st.masses,
            &st.external,
            &st.lim_s,
            &st.lim_k,
            &mut c2,
            &mut f2,
        )
        .unwrap();
        assert_eq!(c1, c2);
        assert_eq!(f1, f2);
    }
}

/// Identical stacks on a floor get the same choice, bit for bit, and it is the choice for one
/// stack of their summed masses, forces and limits (each copy carrying its share of the force),
/// beside other stacks, with and without static friction above kinetic. The problem is
/// invariant under swapping identical stacks and strictly convex, so its minimiser treats them
/// alike; solved one by one, round-off in the coupled solve used to tell them apart (the
/// integrator then broke three copies of one block loose one at a time and stuck them again
/// without end).
#[test]
fn identical_stacks_get_the_same_choice_as_one_stack_of_their_mass() {
    let mut rng = Rng::new(37);
    for round in 0..3000 {
        let gap = round % 2 == 1;
        // One random stack copied `n` times, then a random other stack (or none).
        let base = random_state(&mut rng, gap);
        let copies = [2, 3, 4, 6, 16][rng.below(5)];
        let other = (rng.unit() < 0.5).then(|| random_state(&mut rng, gap));
        let accel_floor = rng.normal();
        let floor_mass = rng.log_range(0.5, 5.0);
        let build = |w: &[f64]| {
            let mut t = Tree {
                st: State {
                    masses: vec![floor_mass],
                    external: vec![floor_mass * G * accel_floor],
                    lim_s: vec![],
                    lim_k: vec![],
                    given: vec![],
                },
                below: vec![],
            };
            let stacks = w
                .iter()
                .map(|&w| (&base, w))
                .chain(other.iter().map(|o| (o, 1.0)));
            for (s, w) in stacks {
                for i in 0..s.given.len() {
                    let at = t.below.len();
                    t.below.push(if i == 0 { 0 } else { at });
                    t.st.masses.push(w * s.masses[i + 1]);
                    t.st.external.push(w * s.external[i + 1]);
                    t.st.lim_s.push(w * s.lim_s[i]);
                    t.st.lim_k.push(w * s.lim_k[i]);
                    t.st.given.push(s.given[i]);
                }
            }
            t
        };
        let run = |t: &Tree| {
            let n = t.st.given.len();
            let (mut contacts, mut force) = (t.st.given.clone(), vec![0.0; n]);
            ContactSelector::new(n)
                .select_tree(
                    &t.below,
                    &t.st.masses,
                    &t.st.external,
                    &t.st.lim_s,
                    &t.st.lim_k,
                    &mut contacts,
                    &mut force,
                )
                .unwrap();
            (contacts, force)
        };
        let many = build(&vec![1.0; copies]);
        let one = build(&[copies as f64]);
        let (c_many, f_many) = run(&many);
        let (c_one, f_one) = run(&one);
        let p = base.given.len();
        let scale = many
            .st
            .lim_s
            .iter()
            .chain(many.st.external.iter())
            .fold(0.0f64, |m, x| m.max(x.abs()));
        for c in 0..copies {
            for i in 0..p {
                let k = c * p + i;
                assert_eq!(c_many[k], c_many[i], "copy {c}, interface {i}");
                assert_eq!(
                    f_many[k].to_bits(),
                    f_many[i].to_bits(),
                    "copy {c}, interface {i}"
                );
                assert_eq!(c_many[k], c_one[i], "copy {c}, interface {i}");
                let share = f_one[i] / copies as f64;
                assert!(
                    (f_many[k] - share).abs() <= 1e-12 * scale,
                    "{} vs {share}",
                    f_many[k]
                );
            }
        }
        // The other stack's choice is the same beside the copies as beside the heavy stack.
        assert_eq!(c_many[copies * p..], c_one[p..]);
        if gap {
            assert!(consistent_tree(&many.st, &many.below, &c_many, 1e-9));
        }
    }
}
