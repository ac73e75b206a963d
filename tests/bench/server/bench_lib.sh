# Shared by the server benchmarks (sourced): nginx's configuration and a wait
# for a port. nginx runs as the benchmarks' reference: 2 workers, sendfile,
# no access log, keep-alive without a request limit, every temp path in WORK.

# write_nginx_conf WORK PORT 'server-block-body'  → WORK/nginx.conf
write_nginx_conf() {
  cat >"$1/nginx.conf" <<CONF
worker_processes 2;
pid $1/nginx.pid;
error_log $1/nginx.err;
events { worker_connections 4096; }
http {
  access_log off;
  sendfile on; tcp_nopush on; tcp_nodelay on;
  keepalive_requests 1000000;
  open_file_cache max=10000;
  types { model/gltf-binary glb; application/json json; }
  default_type application/octet-stream;
  client_body_temp_path $1; proxy_temp_path $1; fastcgi_temp_path $1;
  uwsgi_temp_path $1; scgi_temp_path $1;
  server { listen 127.0.0.1:$2; $3 }
}
CONF
}

# wait_port PORT: until something listens on 127.0.0.1:PORT (at most 10 s).
wait_port() {
  for _ in $(seq 200); do (exec 3<>/dev/tcp/127.0.0.1/$1) 2>/dev/null && return; sleep 0.05; done
  echo "port $1 never opened" >&2
  exit 1
}
