# shellcheck shell=sh
# still_demo FILE SIZE END LAYERS INTEGRATOR: writes the still demo job to FILE (sourced by the
# integration tests and the benchmarks): the demo room, its animation stopped at 0.5 s and its
# camera still, SIZE (WxH) pixels, frames 0 to END, the given `layers:` and `integrator:` values.
# A static shot, for the temporal caches' and accumulators' steady state and for convergence
# against the reference. Run from the repository root.
still_demo() {
    cat >"$1" <<JOB
scene: $PWD/jobs/demo/room.gltf
output: still/frame.####.exr
resolution: [${2%x*}, ${2#*x}]
frames: {start: 0, end: $3, rate: 24}
camera:
  fov_y_deg: 40
  keys:
    - {t: 0, position: [0, 1.0, 3.6], look_at: [0, 0.9, 0]}
animation: {clips: ["Demo"], offset_s: 0.5, speed: 0, loop: true}
lights:
  - {type: point, position: [0.2, 1.3, 2.6], color: [1.0, 0.95, 0.9], intensity: 1.2}
layers: $4
integrator: $5
JOB
}
