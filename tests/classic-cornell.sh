# shellcheck shell=sh
# classic_cornell FILE GLB SIZE END: writes to FILE a job of the Cornell box GLB (the shared
# scenes' cornell-box/CornellBox.glb) as the classic view frames it (sourced by the integration
# tests and the benchmarks): SIZE (WxH) pixels, frames 0 to END, the camera at (-278, 273, 800)
# looking down -z, then the job's remaining lines (lights, layers, integrator) from standard
# input.
classic_cornell() {
    {
        cat <<JOB
scene: $(cd "$(dirname "$2")" && pwd)/$(basename "$2")
output: frame.####.exr
resolution: [${3%x*}, ${3#*x}]
frames: {start: 0, end: $4, rate: 24}
camera: {fov_y_deg: 39.3, keys: [{t: 0, position: [-278, 273, 800], look_at: [-278, 273, 0]}]}
JOB
        cat
    } >"$1"
}
