function jenkins_oscillator(nlvib_src, H, N, Om_s, Om_e, ds, out_prefix, repeats)
% The one-DOF Jenkins oscillator: m = 1 kg, k = 1 N/m to ground, c = 0.05 N s/m, a
% Jenkins element (elasticDryFriction: stiffness 2 N/m, slip limit muN = 0.1 N) to ground,
% 0.1 N harmonic force; its FRF from Om_s to Om_e (rad/s) by NLvib's sequential
% continuation (step ds rad/s), H harmonics, N samples per period, fsolve at
% TolFun = TolX = 1e-10. The continuation runs `repeats` times in this session (the first
% cold). Writes <out_prefix>_points.csv (Om, rms, harmonics c0, c1, s1, ..., fsolve
% iterations) and <out_prefix>_summary.csv (per run: wall and processor time (s), points,
% fsolve iterations).
addpath(nlvib_src);
addpath(fullfile(nlvib_src, 'MechanicalSystems'));

jenkins = struct('type', 'elasticDryFriction', 'stiffness', 2, ...
    'friction_limit_force', 0.1, 'ishysteretic', 1);
oscillator = SingleMassOscillator(1, 0.05, 1, {jenkins}, 0.1);

Q1 = 0.1/(-Om_s^2 + 1i*Om_s*0.05 + 3);   % the stuck linear response
x0 = zeros(2*H+1, 1);
x0(2:3) = [real(Q1); -imag(Q1)];
Sopt = struct('flag', 0, 'stepadapt', 0, 'Dscale', [abs(Q1)*ones(size(x0)); Om_s]);
Solopt = optimset('Display', 'off', 'Jacobian', 'on', 'MaxIter', 50, ...
    'TolFun', 1e-10, 'TolX', 1e-10);
times = zeros(repeats, 2);
for r = 1:repeats
    t0 = tic; c0 = cputime;
    [X, Solinfo] = solve_and_continue(x0, @(X) HB_residual(X, oscillator, H, N, 'FRF'), ...
        Om_s, Om_e, ds, Sopt, {}, Solopt);
    times(r, :) = [toc(t0), cputime - c0];
end
Om = X(end, :)';
Q = X(1:end-1, :)';
rms = sqrt(Q(:, 1).^2 + sum(Q(:, 2:end).^2, 2)/2);
dlmwrite([out_prefix '_points.csv'], [Om, rms, Q, Solinfo.NIT(:)], 'precision', '%.16e');
dlmwrite([out_prefix '_summary.csv'], [times, repmat([numel(Om), sum(Solinfo.NIT)], ...
    repeats, 1)], 'precision', '%.16e');
end
