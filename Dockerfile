# tinsmith — multi-stage image on Debian bookworm.
# builder: the same tools/setup.sh a developer runs, then a Release build.
# runtime: only the shared libraries the binary links, the binary, non-root.
FROM debian:bookworm AS builder
WORKDIR /src
COPY tools/setup.sh tools/setup.sh
RUN bash tools/setup.sh && rm -rf /var/lib/apt/lists/*
COPY . .
RUN cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DTINSMITH_TESTS=OFF -DTINSMITH_BENCHMARKS=OFF \
 && cmake --build build -j"$(nproc)" --target tinsmith \
 && strip build/bin/tinsmith

FROM debian:bookworm AS runtime
# The packages of the libraries the binary links (readelf -d: NEEDED; checked
# against ldd build/release/bin/tinsmith), plus proj-data (proj.db and the
# EGM96 grid) and curl for the health check. tinygltf is linked away (only
# its headers are used) and nothing links libgomp, so neither is here.
RUN apt-get update \
 && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends \
      libgdal32 libproj25 proj-data libgeographiclib23 libopenexr-3-1-30 libimath-3-1-29 libdraco7 \
      libsqlite3-0 libtomlplusplus3 zlib1g libbrotli1 \
      curl \
 && rm -rf /var/lib/apt/lists/* \
 && useradd --system --create-home --home-dir /var/lib/tinsmith tinsmith
COPY --from=builder /src/build/bin/tinsmith /usr/local/bin/tinsmith
USER tinsmith
WORKDIR /var/lib/tinsmith
VOLUME ["/var/lib/tinsmith/stores"]
EXPOSE 8080
HEALTHCHECK --interval=30s --timeout=3s --start-period=5s \
  CMD curl -fsS http://127.0.0.1:8080/health || exit 1
ENTRYPOINT ["tinsmith"]
CMD ["serve", "--host", "0.0.0.0", "--port", "8080", "/var/lib/tinsmith/stores"]
