#!/usr/bin/env python3
"""Deliberately broken lines, and the tests that must fail on them.

Each mutation replaces one exact piece of the library's code; its test must then fail, with a
message holding the given text. The mutations of one round are applied at once (one build per
round; two mutations caught by one test are in different rounds), each named test is run, and
the files are restored whatever happens:

    python3 scripts/mutation_check.py            # every mutation
    python3 scripts/mutation_check.py --list     # what each breaks, and its test
    python3 scripts/mutation_check.py --only registration   # those whose description holds it

Standard library only. Run from the repository's root on a clean work tree; it builds the test
profile (CARGO_INCREMENTAL=0), so it takes a few minutes.
"""

import argparse
import os
import subprocess
import sys

# (round, what is broken, file, exact old text, new text, cargo test arguments, text the failure shows);
# old text None: one more test of the mutation before it
MUTATIONS = [
    (
        1,
        "a prediction takes the truth with the fewest votes",
        "src/metrics/object_matching.rs",
        "let top = votes.iter().max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0)));",
        "let top = votes.iter().min_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0)));",
        ["-p", "catmap", "--lib", "object_matching::"],
        "panicked",
    ),
    (
        1,
        "a depth camera's noise allowance doubled",
        "src/config/mod.rs",
        "DepthImages::Camera => (DepthSmoothing::Bilateral, 0.0025),",
        "DepthImages::Camera => (DepthSmoothing::Bilateral, 0.005),",
        ["-p", "catmap", "--lib", "cell_evidence::"],
        "0.0025",
    ),
    (
        1,
        "every free draw is the box's centre",
        "src/objects/hidden_space.rs",
        "        let pick = rng.random_range(0..all);\n",
        "        let pick = rng.random_range(0..all);\n        if pick < all {\n            return Some(self.world_from_box * Point3::origin());\n        }\n",
        ["-p", "catmap", "--lib", "hidden_gap"],
        "panicked",
    ),
    (
        1,
        "a failed training step is not recorded",
        "systems/src/failed_step.rs",
        "        if self.0.is_none() {\n            self.0 = Some(StepFailure {",
        "        if self.0.is_some() {\n            self.0 = Some(StepFailure {",
        ["--test", "suite", "failed_step"],
        "panicked",
    ),
    (
        2,
        "a checkpoint is written after a failed step",
        "systems/src/mapper.rs",
        "        if self.failed {\n            return Err(MapperError::Stopped);\n        }\n        let (state, tensors)",
        "        let (state, tensors)",
        ["--test", "suite", "failed_step"],
        "panicked",
    ),
    (
        2,
        "registration keeps the coarse search's poses, unrefined",
        "src/registration/register.rs",
        "let (pose, icp) = fine.refine_fully(coarse_fits[k].0, cfg);",
        "let (pose, icp) = (coarse_fits[k].0, IcpCounts::default());",
        ["--test", "suite", "registration_trials::fifty"],
        "the failing trials",
    ),
    (
        2,
        "an aligned member's box turned 2.9° about up",
        "src/categories/nocs.rs",
        "let world_from_box = template_from_object.inverse() * rep_box;",
        "let world_from_box = template_from_object.inverse() * rep_box * Isometry3::rotation(Vector3::z() * 0.05);",
        ["--test", "suite", "category_registration"],
        "boxes off",
    ),
    (
        1,
        "a mask joins an object only when it overlaps it twice as much",
        "src/objects/association_config.rs",
        "            min_overlap: 0.3,",
        "            min_overlap: 0.6,",
        ["-p", "catmap", "--lib", "per_frame_ids_of_a_small_scene"],
        "panicked",
    ),
    (
        1,
        "the training report gives the category phase's end for the phase after the stream",
        "systems/src/training_report.rs",
        "after_stream_end: phases.after_stream_end,",
        "after_stream_end: phases.category_end,",
        ["--test", "suite", "run_phases"],
        "panicked",
    ),
]


def cargo_test(args):
    env = dict(os.environ, CARGO_INCREMENTAL="0", CARGO_TERM_COLOR="never")
    return subprocess.run(["cargo", "test", *args], env=env, capture_output=True, text=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--list", action="store_true", help="list the mutations and their tests")
    parser.add_argument("--only", metavar="TEXT", help="only the mutations whose description holds TEXT")
    opts = parser.parse_args()
    global MUTATIONS
    if opts.only:
        MUTATIONS = [m for m in MUTATIONS if opts.only in m[1]]
    if opts.list:
        for round_, what, path, _, _, test, _ in MUTATIONS:
            print(f"round {round_}: {what}\n    {path}\n    cargo test {' '.join(test)}")
        return 0
    survived = 0
    for round_ in sorted({m[0] for m in MUTATIONS}):
        mutations = [m for m in MUTATIONS if m[0] == round_]
        originals = {}
        try:
            for _, what, path, old, new, _, _ in mutations:
                if old is None:  # another test of the mutation above
                    continue
                current = open(path).read()
                originals.setdefault(path, current)
                if current.count(old) != 1:
                    print(f"cannot apply '{what}': {path} holds its line {current.count(old)} times", file=sys.stderr)
                    return 2
                open(path, "w").write(current.replace(old, new, 1))
            build = cargo_test(["--workspace", "--no-run"])
            if build.returncode != 0:
                print(build.stderr[-4000:], file=sys.stderr)
                print(f"round {round_}: the mutated code does not build", file=sys.stderr)
                return 2
            for _, what, path, _, _, test, shows in mutations:
                run = cargo_test(test)
                caught = run.returncode != 0 and shows in (run.stdout + run.stderr)
                survived += not caught
                print(f"{'caught  ' if caught else 'SURVIVED'} {what} ({path}): cargo test {' '.join(test)}", flush=True)
        finally:
            for path, text in originals.items():
                open(path, "w").write(text)
    print(f"{len(MUTATIONS) - survived} of {len(MUTATIONS)} mutations caught")
    return 1 if survived else 0


if __name__ == "__main__":
    sys.exit(main())
