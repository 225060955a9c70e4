# dancegen in a container: the `dancegen` binary and the bundled models, for batch runs on a
# cluster (docs/scale-out.md) or `dancegen serve` behind a proxy.
#
#   docker build -t dancegen .
#   docker run --rm -v "$PWD/work:/work" dancegen batch /work/manifest.jsonl --out /work/out
#
# Build stage: the same toolchain as rust-toolchain / Cargo.toml's rust-version, the C library
# the resampler links (libsoxr), and the lock file's exact crates.
FROM rust:1.95-bookworm AS build
RUN apt-get update \
    && apt-get install -y --no-install-recommends libsoxr-dev pkg-config \
    && rm -rf /var/lib/apt/lists/*
WORKDIR /src
COPY . .
RUN cargo build --release --locked -p dancegen-cli \
    && strip target/release/dancegen

# Run stage: the binary in /usr/bin and the models in /usr/share/dancegen/models, where a
# packaged install finds them (crates/dancegen-generate/src/models.rs, rule 2), so no
# DANCEGEN_MODEL_DIR is needed. ffmpeg only for `-o dance.mp4` previews.
FROM debian:bookworm-slim
RUN apt-get update \
    && apt-get install -y --no-install-recommends libsoxr0 libgomp1 ffmpeg ca-certificates \
    && rm -rf /var/lib/apt/lists/*
COPY --from=build /src/target/release/dancegen /usr/bin/dancegen
COPY models /usr/share/dancegen/models
COPY LICENSE-MIT LICENSE-APACHE NOTICE /usr/share/doc/dancegen/
# Not root: batch outputs on a shared volume belong to this user (override with --user).
RUN useradd --create-home --uid 1000 dancegen
USER dancegen
WORKDIR /work
ENTRYPOINT ["dancegen"]
CMD ["--help"]
