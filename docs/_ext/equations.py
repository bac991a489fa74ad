"""The paper's 20 numbered equations in LaTeX, as the compiled paper numbers them.

Copied from the paper's source (``../shared/paper``, S. Duan et al., arXiv:1809.04215),
with its obvious typos kept out of the way (eq. 17's mean uses the product's
covariance). What each states and which functions implement it come from
:data:`sandbox.core.EQUATIONS`; ``docs/_ext/generate.py`` joins the two.
"""

LATEX: dict[int, str] = {
    1: r"y_t = \boldsymbol\psi_t^T \boldsymbol\omega + \epsilon_y, \quad "
       r"p(\mathbf y_{1:T} \mid \boldsymbol\omega) = \prod_{t=1}^T "
       r"\mathcal N(y_t \mid \boldsymbol\psi_t^T \boldsymbol\omega, \sigma_y)",
    2: r"\boldsymbol\omega = (\boldsymbol\Psi_{1:T}^T \boldsymbol\Psi_{1:T})^{-1} "
       r"\boldsymbol\Psi_{1:T}^T \mathbf y_{1:T}",
    3: r"\boldsymbol\Psi_{1:T} = \begin{bmatrix} (\psi_1)_1 & \cdots & (\psi_1)_N \\ "
       r"\vdots & \ddots & \vdots \\ (\psi_T)_1 & \cdots & (\psi_T)_N \end{bmatrix}",
    4: r"p(y_t \mid \boldsymbol\theta) = \int p(y_t \mid \boldsymbol\omega) "
       r"p(\boldsymbol\omega \mid \boldsymbol\theta)\, d\boldsymbol\omega = "
       r"\mathcal N(y_t \mid \boldsymbol\psi_t^T \boldsymbol\mu_\omega, "
       r"\boldsymbol\psi_t^T \boldsymbol\Sigma_\omega \boldsymbol\psi_t + \sigma_y)",
    5: r"\mathbf y_t = [y_{1,t}^H, \dots, y_{p,t}^H, y_{1,t}^R, \dots, y_{q,t}^R]^T",
    6: r"\boldsymbol\omega_i^T = [(\boldsymbol\omega_1^H)^T, \dots, (\boldsymbol\omega_p^H)^T, "
       r"(\boldsymbol\omega_1^R)^T, \dots, (\boldsymbol\omega_q^R)^T]",
    7: r"\mathbf H_t = \operatorname{diag}((\boldsymbol\psi_t^T)_1, \dots, "
       r"(\boldsymbol\psi_t^T)_p, (\boldsymbol\psi_t^T)_1, \dots, (\boldsymbol\psi_t^T)_q)",
    8: r"\begin{aligned} \boldsymbol\mu_\omega^{new} &= \boldsymbol\mu_\omega + \mathbf K "
       r"(\mathbf y^o_{t-t'} - \mathbf H_{t-t'} \boldsymbol\mu_\omega), \quad "
       r"\boldsymbol\Sigma_\omega^{new} = \boldsymbol\Sigma_\omega - \mathbf K \mathbf H_{t-t'} "
       r"\boldsymbol\Sigma_\omega, \\ \mathbf K &= \boldsymbol\Sigma_\omega \mathbf H^T_{t-t'} "
       r"(\boldsymbol\Sigma^o_y + \mathbf H_{t-t'} \boldsymbol\Sigma_\omega "
       r"\mathbf H^T_{t-t'})^{-1} \end{aligned}",
    9: r"\mathbf H_{t-t'} = \begin{bmatrix} (\boldsymbol\psi_t^T)_1 & & & & \\ & \ddots & & & "
       r"\\ & & (\boldsymbol\psi_t^T)_p & & \\ & & & 0_1 & \\ & & & & \ddots \\ "
       r"& & & & 0_q \end{bmatrix}",
    10: r"\alpha_{i,dow} = T_i / T_{nom,dow}",
    11: r"p(\alpha_{dow} \mid \mathbf y^o_{t-t'}, \boldsymbol\theta) \propto "
        r"p(\mathbf y_{t-t'} \mid \alpha_{dow}, \boldsymbol\theta)\, p(\alpha_{dow})",
    12: r"p(\mathbf y_{t-t'} \mid \alpha_{dow}, \boldsymbol\theta) = \int "
        r"p(\mathbf y^o_{t-t'} \mid \boldsymbol\omega, \alpha_{dow})\, p(\boldsymbol\omega)\, "
        r"d\boldsymbol\omega",
    13: r"\alpha^*_{dow} = \arg\max_{\alpha_{dow}} p(\alpha_{dow} \mid \mathbf y^o_{t-t'}, "
        r"\boldsymbol\theta)",
    14: r"p(k \mid \mathbf y^o_{t-t'}) \propto p(\mathbf y^o_{t-t'} \mid \boldsymbol\theta_k, "
        r"\alpha^*_{dow})\, p(k)",
    15: r"p(\mathbf y^o_{t-t'}; \boldsymbol\theta_k, \alpha^*_{dow}) = \int "
        r"p(\mathbf y^o_{t-t'} \mid \mathbf H^o_{t-t'} \boldsymbol\omega, \boldsymbol\Sigma_y)\, "
        r"p(\boldsymbol\omega; \boldsymbol\theta_k)\, d\boldsymbol\omega",
    16: r"p^*(\tau) \propto \prod_t \prod_i p_i(\mathbf y_t)^{a_t^{[i]}}, \quad "
        r"p_i(\mathbf y_t) = \int p_i(\mathbf y_t \mid \boldsymbol\omega^{[i]})\, "
        r"p_i(\boldsymbol\omega^{[i]})\, d\boldsymbol\omega^{[i]}",
    17: r"\boldsymbol\Sigma^*_t = \Big(\sum_i (\boldsymbol\Sigma^{[i]}_t / a^{[i]}_t)^{-1}"
        r"\Big)^{-1}, \quad \boldsymbol\mu^*_t = \boldsymbol\Sigma^*_t \sum_i "
        r"(\boldsymbol\Sigma^{[i]}_t / a^{[i]}_t)^{-1} \boldsymbol\mu^{[i]}_t",
    18: r"a_{rise}[t] = \frac{1}{1 + e^{-lt}}, \quad a_{fall}[t] = \frac{1}{1 + e^{lt}}",
    19: r"\nabla e_p = e_{p,sow(f)} - e_{p,dow\_t}, \quad \nabla e_q = e_{q,sow(f)} - "
        r"e_{q,dow\_t}, \quad \nabla e_\phi = e_{\phi,sow(f)} - e_{\phi,dow\_t}",
    20: r"\min m_{dow\_t} = \gamma_p \frac{e_{p,dow\_t}}{\max_t e_{p,dow\_t}} + \gamma_q "
        r"\frac{e_{q,dow\_t}}{\max_t e_{q,dow\_t}} + \gamma_\phi \frac{e_{\phi,dow\_t}}"
        r"{\max_t e_{\phi,dow\_t}}",
}
