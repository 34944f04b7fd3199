function ex08_jenkins(nlvib_src, kt, H, N, ds, out_prefix, repeats)
% NLvib's example 08 (friction-damped Euler-Bernoulli beam, 9 nodes clamped-free) with its
% Coulomb element replaced by a Jenkins element (elasticDryFriction: tangential stiffness
% kt N/m, slip limit muN = 1.5 N) at node 4, 0.2 N at the tip, damping beta*K with 1 % at
% the first stuck mode; the whole FRF from 1.5 om_fixed down to 0.9 om_free by the
% example's sequential continuation (step ds rad/s), H harmonics, N samples per period.
% fsolve runs at TolFun = TolX = 1e-10 (with looser tolerances NLvib accepts unconverged
% points). The continuation runs `repeats` times in this session; the first is cold.
% Writes <out_prefix>_points.csv (Om in rad/s, tip rms, the tip's harmonics
% c0, c1, s1, ..., fsolve iterations) and <out_prefix>_summary.csv (per run: wall and
% processor time (s), points, fsolve iterations, om_free, om_fixed (rad/s)).
addpath(nlvib_src);
addpath(fullfile(nlvib_src, 'MechanicalSystems'));

len = 2; height = .05*len; thickness = 3*height; E = 185e9; rho = 7830;
n_nodes = 9;
beam = FE_EulerBernoulliBeam(len, height, thickness, E, rho, 'clamped-free', n_nodes);
add_nonlinear_attachment(beam, 4, 'trans', 'elasticDryFriction', ...
    'stiffness', kt, 'friction_limit_force', 1.5, 'ishysteretic', 1);
T_nl = beam.nonlinear_elements{1}.force_direction';
T_tip = beam.L(end-1, :);

[~, OM2] = eig(beam.K, beam.M); om_free = sort(sqrt(diag(OM2)));
inl = find(T_nl); B = eye(length(beam.M)); B(:, inl) = [];
[~, OM2] = eig(B'*beam.K*B, B'*beam.M*B); om_fixed = sort(sqrt(diag(OM2)));

Om_s = 1.5*om_fixed(1); Om_e = .9*om_free(1);
add_forcing(beam, n_nodes, 'trans', .2);
beam.D = (2*1e-2/om_fixed(1))*beam.K;

Fex1 = beam.Fex1;
Q1 = B*((B'*(-Om_s^2*beam.M + 1i*Om_s*beam.D + beam.K)*B)\(B'*Fex1));
qscl = mean(abs(Q1));
x0 = zeros((2*H+1)*size(Q1,1), 1);
x0(size(Q1,1)+(1:2*size(Q1,1))) = [real(Q1); -imag(Q1)];

Sopt = struct('flag', 0, 'stepadapt', 0, 'Dscale', [qscl*ones(size(x0)); Om_s]);
Solopt = optimset('Display', 'off', 'Jacobian', 'on', 'MaxIter', 50, ...
    'TolFun', 1e-10, 'TolX', 1e-10);
times = zeros(repeats, 2);
for r = 1:repeats
    t0 = tic; c0 = cputime;
    [X, Solinfo] = solve_and_continue(x0, @(X) HB_residual(X, beam, H, N, 'FRF'), ...
        Om_s, Om_e, ds, Sopt, {}, Solopt);
    times(r, :) = [toc(t0), cputime - c0];
end
Om = X(end, :)';
Qtip = (kron(eye(2*H+1), T_tip)*X(1:end-1, :))';
rms = sqrt(sum(Qtip.^2, 2))/sqrt(2);
dlmwrite([out_prefix '_points.csv'], [Om, rms, Qtip, Solinfo.NIT(:)], 'precision', '%.16e');
dlmwrite([out_prefix '_summary.csv'], [times, repmat([numel(Om), sum(Solinfo.NIT), ...
    om_free(1), om_fixed(1)], repeats, 1)], 'precision', '%.16e');
end
